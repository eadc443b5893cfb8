"""Closing a TCP socket so that the peer sees it at once: the simple_message driver's two
connections and the simulated controller's listeners and clients end the same way."""

import socket

__all__ = ["close_socket"]


def close_socket(sock) -> None:
    """Shut ``sock`` down both ways (a reader blocked in recv() on it wakes), then close it;
    None or an already closed socket is fine."""
    if sock is None:
        return
    try:
        sock.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass  # not connected (a listener) or already gone: closing is all that is left
    sock.close()
