"""The messages between the episode recorder (the framework's venv, rospy) and the LeRobot
writer process (``.venv-lerobot``, see ``lerobot_writer``), over the writer's stdin.

One message is a 4-byte big-endian length, a JSON header of that length, then the arrays
the header lists (``[name, dtype, shape, bytes]`` each: NumPy's dtype string such as
``<f4``, the shape, the byte count), each its raw C-order bytes, so that both interpreters
need nothing beyond NumPy and no pickle crosses the pipe. Only plain numbers (bool, int,
uint, float) are accepted. (Raw bytes rather than ``.npy`` blobs: parsing a ``.npy`` header
costs ~60 us an array, most of the writer's time per frame.) A malformed message raises
``WireError`` naming what was wrong. Replies come back as one JSON object a line on
the writer's stdout.

Plain Python, no ROS and no framework import: the writer's venv imports it from this folder.
"""

import json
import math
import struct

import numpy as np

__all__ = ["WireError", "encode", "read_message", "MAX_HEADER_BYTES"]

MAX_HEADER_BYTES = 1 << 20  # a header is a few hundred bytes; a bigger one is garbage
_KINDS = "biuf"  # bool, int, uint, float: what a frame holds
_LENGTH = struct.Struct(">I")


class WireError(ValueError):
    """A message that cannot be decoded (its reason in the text)."""


def encode(header: dict, arrays: dict | None = None) -> bytes:
    """One message: ``header`` (JSON-able) plus named NumPy arrays."""
    entries, blobs = [], []
    for name, value in (arrays or {}).items():
        value = np.ascontiguousarray(value)
        if value.dtype.kind not in _KINDS:
            raise WireError(f"array {name!r}: dtype {value.dtype} is not a plain number")
        blobs.append(value.tobytes())
        entries.append([name, value.dtype.str, list(value.shape), len(blobs[-1])])
    head = dict(header, arrays=entries)
    blob = json.dumps(head, separators=(",", ":")).encode("utf-8")
    return b"".join([_LENGTH.pack(len(blob)), blob, *blobs])


def _array(entry, data_of) -> tuple:
    """(name, array) from a header's entry; ``data_of(n)`` reads the n bytes."""
    if not (
        isinstance(entry, list)
        and len(entry) == 4
        and isinstance(entry[1], str)
        and isinstance(entry[2], list)
        and all(isinstance(n, int) and n >= 0 for n in entry[2])
        and isinstance(entry[3], int)
        and entry[3] >= 0
    ):
        raise WireError(f"array entry {entry!r} is not [name, dtype, shape, bytes]")
    name, dtype, shape, size = entry
    try:
        dtype = np.dtype(dtype)
    except TypeError:
        raise WireError(f"array {name!r}: dtype {entry[1]!r} is not NumPy's") from None
    if dtype.kind not in _KINDS or dtype.hasobject:
        raise WireError(f"array {name!r}: dtype {dtype} is not a plain number")
    if size != math.prod(shape) * dtype.itemsize:
        raise WireError(f"array {name!r}: {size} bytes for {dtype} {shape}")
    return str(name), np.frombuffer(data_of(size), dtype=dtype).reshape(shape)


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
        name, value = _array(entry, lambda n: _read_exactly(stream, n))
        arrays[name] = value
    return header, arrays
