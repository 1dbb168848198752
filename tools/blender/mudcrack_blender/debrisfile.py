"""Reading the plates mode's debris points (surface/debris.####.ply) in pure Python: no bpy, no
numpy (Debian's Blender 3.4 has none).

The layout is exactly the one pipeline/io/debris_io.cpp writes (docs/physics.md 5.7): a binary
little-endian PLY with one element, `vertex`, whose properties are, in this order,
    float x y z, float vx vy vz, float pscale, int id, int piece
(36 bytes per point, no padding) and no faces. Other PLY files are refused with a message naming
the file: a general PLY reader is not needed, and a strict one catches a file of another layout
instead of reading garbage from it.
"""
from array import array
import sys

from .meshfile import MeshFileError

__all__ = ["DebrisData", "DebrisFileError", "read_debris_ply", "DEBRIS_PROPERTIES"]

# (type, name) of each vertex property, in file order (debris_io.cpp kProperties)
DEBRIS_PROPERTIES = (("float", "x"), ("float", "y"), ("float", "z"),
                     ("float", "vx"), ("float", "vy"), ("float", "vz"),
                     ("float", "pscale"), ("int", "id"), ("int", "piece"))
_WORDS_PER_POINT = len(DEBRIS_PROPERTIES)  # every property is 4 bytes wide
_FORMAT = "format binary_little_endian 1.0"

if sys.byteorder != "little":  # the file is little-endian; array.frombytes reads native order
    raise ImportError("mudcrack_blender.debrisfile: big-endian machines are not supported")


class DebrisFileError(MeshFileError):
    """A debris file that cannot be read: the message names the file and what is wrong. A
    MeshFileError, so the playback reports it like an unreadable mesh."""


class DebrisData:
    """One frame's debris as flat arrays: positions and velocities (3 n floats, y-up, m and m/s),
    pscale (n floats: radius, m), ids and pieces (n ints: the grain, and the piece it tore from
    or -1)."""

    __slots__ = ("positions", "velocities", "pscale", "ids", "pieces")

    def __init__(self, count):
        self.positions = array("f", bytes(12 * count))
        self.velocities = array("f", bytes(12 * count))
        self.pscale = array("f")
        self.ids = array("i")
        self.pieces = array("i")

    @property
    def point_count(self):
        return len(self.pscale)


def _read_header(blob, path):
    """(point count, byte offset of the body) of a debris PLY's header. Raises DebrisFileError."""
    end = blob.find(b"end_header\n")
    if not blob.startswith(b"ply\n") or end < 0:
        raise DebrisFileError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    lines = [line.strip() for line in blob[:end].decode("ascii", "replace").splitlines()[1:]]
    lines = [line for line in lines if line and not line.startswith(("comment", "obj_info"))]
    count, properties = None, []
    for line in lines:
        words = line.split()
        if words[0] == "element":
            if count is not None or len(words) != 3 or words[1] != "vertex" or not words[2].isdigit():
                raise DebrisFileError(f"{path}: '{line}': a debris file has one element, 'vertex <count>'")
            count = int(words[2])
        elif words[0] == "property" and len(words) == 3:
            properties.append((words[1], words[2]))
        elif line != _FORMAT:
            raise DebrisFileError(f"{path}: '{line}': expected '{_FORMAT}' (mudcrack writes binary little-endian)")
    if _FORMAT not in lines:
        raise DebrisFileError(f"{path}: no '{_FORMAT}' line")
    if count is None or tuple(properties) != DEBRIS_PROPERTIES:
        want = " ".join(f"{t} {n}," for t, n in DEBRIS_PROPERTIES).rstrip(",")
        raise DebrisFileError(f"{path}: not a mudcrack debris file: its vertex properties are not {want} "
                              "(docs/physics.md 5.7)")
    return count, end + len(b"end_header\n")


def read_debris_ply(path):
    """The debris points of `path`, a file mc-surface wrote. Raises DebrisFileError naming the file."""
    try:
        with open(path, "rb") as f:
            blob = f.read()
    except OSError as e:
        raise DebrisFileError(f"{path}: cannot read: {e.strerror}") from None
    count, body_start = _read_header(blob, path)
    body = memoryview(blob)[body_start:]
    if len(body) != 4 * _WORDS_PER_POINT * count:
        raise DebrisFileError(f"{path}: truncated or too long: {count} points take {4 * _WORDS_PER_POINT * count} "
                              f"bytes after the header; the file holds {len(body)}")
    # the records interleave floats and ints of the same width: read the body once as each type
    # and pick every property's column out with a stride
    floats, ints = array("f"), array("i")
    floats.frombytes(body)
    ints.frombytes(body)
    out = DebrisData(count)
    for k in range(3):
        out.positions[k::3] = floats[k::_WORDS_PER_POINT]
        out.velocities[k::3] = floats[3 + k::_WORDS_PER_POINT]
    out.pscale = floats[6::_WORDS_PER_POINT]
    out.ids = ints[7::_WORDS_PER_POINT]
    out.pieces = ints[8::_WORDS_PER_POINT]
    return out
