"""The messages between the episode recorder (the framework's venv, rospy) and the LeRobot
writer process (``.venv-lerobot``, see ``lerobot_writer``), over the writer's stdin.

One message is a 4-byte big-endian length, a JSON header of that length, then the arrays
the header lists (``[name, bytes]`` each), each in NumPy's own ``.npy`` format (``numpy.lib.format``), so that both
interpreters need nothing beyond NumPy and no pickle crosses the pipe. A malformed message
raises ``WireError`` naming what was wrong. Replies come back as one JSON object a line on
the writer's stdout.

Plain Python, no ROS and no framework import: the writer's venv imports it from this folder.
"""

import io
import json
import struct

import numpy as np

__all__ = ["WireError", "encode", "read_message", "MAX_HEADER_BYTES"]

MAX_HEADER_BYTES = 1 << 20  # a header is a few hundred bytes; a bigger one is garbage
_LENGTH = struct.Struct(">I")


class WireError(ValueError):
    """A message that cannot be decoded (its reason in the text)."""


def encode(header: dict, arrays: dict | None = None) -> bytes:
    """One message: ``header`` (JSON-able) plus named NumPy arrays."""
    blobs = []
    for value in (arrays or {}).values():
        out = io.BytesIO()
        np.lib.format.write_array(out, np.ascontiguousarray(value), allow_pickle=False)
        blobs.append(out.getvalue())
    head = dict(header, arrays=[[name, len(b)] for name, b in zip(arrays or {}, blobs)])
    blob = json.dumps(head, separators=(",", ":")).encode("utf-8")
    return b"".join([_LENGTH.pack(len(blob)), blob, *blobs])


def _read_exactly(stream, n: int) -> bytes:
    data = stream.read(n)
    if data is None or len(data) < n:
        raise EOFError(f"stream ended inside a message ({0 if not data else len(data)} of {n} bytes)")
    return data


def read_message(stream) -> tuple[dict, dict] | None:
    """The next (header, arrays) from a binary stream; None at a clean end of stream."""
    prefix = stream.read(_LENGTH.size)
    if not prefix:
        return None
    if len(prefix) < _LENGTH.size:
        raise EOFError("stream ended inside a message length")
    (length,) = _LENGTH.unpack(prefix)
    if length > MAX_HEADER_BYTES:
        raise WireError(f"header of {length} bytes (at most {MAX_HEADER_BYTES})")
    try:
        header = json.loads(_read_exactly(stream, length).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise WireError(f"header is not JSON: {exc}") from None
    if not isinstance(header, dict) or not isinstance(header.get("arrays", []), list):
        raise WireError("header must be an object with a list 'arrays'")
    arrays = {}
    for entry in header.pop("arrays", []):
        if not (isinstance(entry, list) and len(entry) == 2 and isinstance(entry[1], int) and entry[1] >= 0):
            raise WireError(f"array entry {entry!r} is not [name, bytes]")
        name, size = entry
        try:
            # Read into memory first: NumPy reads real files with fromfile, which a pipe is not.
            arrays[str(name)] = np.lib.format.read_array(io.BytesIO(_read_exactly(stream, size)), allow_pickle=False)
        except ValueError as exc:
            raise WireError(f"array {name!r}: {exc}") from None
    return header, arrays
