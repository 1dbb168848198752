"""Reading the surfacing's per-frame meshes (surface/boundary.####.glb, crack.####.glb) in pure
Python: no bpy, no numpy, no glTF importer.

Why not Blender's glTF importer: Debian 12's Blender 3.4 ships without numpy (python3-numpy is
only a Recommends), and with Debian's numpy 1.24 its importer fails on `numpy.bool`. Importing
through an operator would also create objects, materials and a node hierarchy per frame. A .glb
is a small container (a JSON chunk describing typed arrays in one binary chunk), so reading the
arrays directly is short, exact, and fast: every array is one memcpy into an `array.array`,
which bpy's `foreach_set` takes without a per-element conversion.

`read_mesh_file(path)` returns one `MeshData` (all meshes of the file merged, node transforms
applied) for .glb and .obj; other extensions raise `MeshFileError` naming the file and what is
supported. Conventions of the returned data (mudcrack's, which are the files'):
  * y up, metres, as written (the add-on turns y-up into Blender's z-up once, on the shot's root
    object);
  * `uv0`: texture coordinates with v up (Blender's and OpenGL's convention; glTF stores v down,
    so v is flipped here, as Blender's own glTF importer does);
  * `uv1`: the fragment id in u (mudcrack writes (fragment id, 0) in UV channel 1);
  * `colors`: RGBA floats per vertex, (saturation, logistic(alpha), 0, 1) in mudcrack's files.
"""
from array import array
import json
import math
import os
import struct
import sys

__all__ = ["MeshData", "MeshFileError", "read_mesh_file", "read_glb", "read_obj", "SUPPORTED_EXTENSIONS"]

SUPPORTED_EXTENSIONS = (".glb", ".obj")

# glTF 2.0 accessor component types -> array typecodes, and the scale of normalized integers
_COMPONENT = {5120: ("b", 127.0), 5121: ("B", 255.0), 5122: ("h", 32767.0), 5123: ("H", 65535.0),
              5125: ("I", None), 5126: ("f", None)}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_GLB_MAGIC = 0x46546C67  # "glTF"
_CHUNK_JSON = 0x4E4F534A
_CHUNK_BIN = 0x004E4942
_MODE_TRIANGLES = 4

if sys.byteorder != "little":  # glb is little-endian; array.frombytes reads native order
    raise ImportError("mudcrack_blender.meshfile: big-endian machines are not supported")


class MeshFileError(Exception):
    """A mesh file that cannot be read: the message names the file and what is wrong."""


class MeshData:
    """One triangle mesh as flat arrays (typecode 'f' floats, 'I' indices).

    positions (3 n), normals (3 n or None), uv0 (2 n or None), uv1 (2 n or None),
    colors (4 n or None), indices (3 m): triangle corners, counter-clockwise seen from outside.
    """

    __slots__ = ("positions", "normals", "uv0", "uv1", "colors", "indices")

    def __init__(self):
        self.positions = array("f")
        self.normals = None
        self.uv0 = None
        self.uv1 = None
        self.colors = None
        self.indices = array("I")

    @property
    def vertex_count(self):
        return len(self.positions) // 3

    @property
    def face_count(self):
        return len(self.indices) // 3

    def append(self, other, path):
        """Appends another mesh (its indices shifted). Attributes only one of them has are
        dropped, as the result could not hold them for every vertex."""
        if self.vertex_count == 0 and self.face_count == 0:
            for name in self.__slots__:
                setattr(self, name, getattr(other, name))
            return
        offset = self.vertex_count
        self.positions.extend(other.positions)
        for name in ("normals", "uv0", "uv1", "colors"):
            mine, theirs = getattr(self, name), getattr(other, name)
            if mine is not None and theirs is not None:
                mine.extend(theirs)
            elif mine is not None or theirs is not None:
                print(f"mudcrack_blender: {path}: '{name}' present on some meshes of the file only: dropped",
                      file=sys.stderr)
                setattr(self, name, None)
        self.indices.extend(array("I", (i + offset for i in other.indices)) if offset else other.indices)


def read_mesh_file(path):
    """The meshes of `path` (.glb or .obj), merged into one MeshData. Raises MeshFileError."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".glb":
        return read_glb(path)
    if ext == ".obj":
        return read_obj(path)
    raise MeshFileError(f"{path}: unsupported mesh format '{ext}': the mudcrack add-on reads .glb (mc-surface's "
                        f"default) and .obj; re-run the surfacing with \"surfacing\": {{\"format\": \"glb\"}}")


# ---- glb ------------------------------------------------------------------------------------------

def _mat4_identity():
    return [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


def _mat4_mul(a, b):
    """Column-major 4x4 product a b (glTF stores matrices column-major)."""
    return [sum(a[k * 4 + r] * b[c * 4 + k] for k in range(4)) for c in range(4) for r in range(4)]


def _node_matrix(node):
    """A glTF node's local transform, column-major."""
    if "matrix" in node:
        return [float(x) for x in node["matrix"]]
    tx, ty, tz = node.get("translation", (0.0, 0.0, 0.0))
    qx, qy, qz, qw = node.get("rotation", (0.0, 0.0, 0.0, 1.0))
    sx, sy, sz = node.get("scale", (1.0, 1.0, 1.0))
    # rotation matrix of a unit quaternion, times the scale, then the translation
    r = [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw), 2 * (qx * qz - qy * qw),
         2 * (qx * qy - qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz + qx * qw),
         2 * (qx * qz + qy * qw), 2 * (qy * qz - qx * qw), 1 - 2 * (qx * qx + qy * qy)]
    return [r[0] * sx, r[1] * sx, r[2] * sx, 0.0, r[3] * sy, r[4] * sy, r[5] * sy, 0.0,
            r[6] * sz, r[7] * sz, r[8] * sz, 0.0, tx, ty, tz, 1.0]


def _is_identity(m, tol=1e-12):
    return all(abs(x - y) <= tol for x, y in zip(m, _mat4_identity()))


def _transform(data, m):
    """Applies the 4x4 column-major transform m to positions, and its inverse transpose to normals."""
    p = data.positions
    for i in range(0, len(p), 3):
        x, y, z = p[i], p[i + 1], p[i + 2]
        p[i] = m[0] * x + m[4] * y + m[8] * z + m[12]
        p[i + 1] = m[1] * x + m[5] * y + m[9] * z + m[13]
        p[i + 2] = m[2] * x + m[6] * y + m[10] * z + m[14]
    if data.normals is None:
        return
    # inverse transpose of the upper 3x3 (its cofactor matrix; the scale is dropped by normalizing)
    a = [[m[0], m[4], m[8]], [m[1], m[5], m[9]], [m[2], m[6], m[10]]]
    cof = [[a[(r + 1) % 3][(c + 1) % 3] * a[(r + 2) % 3][(c + 2) % 3] -
            a[(r + 1) % 3][(c + 2) % 3] * a[(r + 2) % 3][(c + 1) % 3] for c in range(3)] for r in range(3)]
    n = data.normals
    for i in range(0, len(n), 3):
        x, y, z = n[i], n[i + 1], n[i + 2]
        tx = cof[0][0] * x + cof[0][1] * y + cof[0][2] * z
        ty = cof[1][0] * x + cof[1][1] * y + cof[1][2] * z
        tz = cof[2][0] * x + cof[2][1] * y + cof[2][2] * z
        length = math.sqrt(tx * tx + ty * ty + tz * tz) or 1.0
        n[i], n[i + 1], n[i + 2] = tx / length, ty / length, tz / length


class _Glb:
    def __init__(self, path):
        self.path = path
        try:
            with open(path, "rb") as f:
                blob = f.read()
        except OSError as e:
            raise MeshFileError(f"{path}: cannot read: {e.strerror}") from None
        if len(blob) < 20:
            raise MeshFileError(f"{path}: not a glb file ({len(blob)} bytes)")
        magic, version, length = struct.unpack_from("<III", blob, 0)
        if magic != _GLB_MAGIC:
            raise MeshFileError(f"{path}: not a glb file (no 'glTF' magic)")
        if version != 2:
            raise MeshFileError(f"{path}: glTF container version {version}: expected 2")
        if length > len(blob):
            raise MeshFileError(f"{path}: truncated: the header says {length} bytes, the file has {len(blob)}")
        self.gltf = None
        self.bin = memoryview(b"")
        offset = 12
        while offset + 8 <= length:
            chunk_length, chunk_type = struct.unpack_from("<II", blob, offset)
            start, end = offset + 8, offset + 8 + chunk_length
            if end > length:
                raise MeshFileError(f"{path}: truncated chunk at byte {offset}")
            if chunk_type == _CHUNK_JSON and self.gltf is None:
                try:
                    self.gltf = json.loads(bytes(blob[start:end]).decode("utf-8"))
                except (UnicodeDecodeError, ValueError) as e:
                    raise MeshFileError(f"{path}: the JSON chunk does not parse: {e}") from None
            elif chunk_type == _CHUNK_BIN and len(self.bin) == 0:
                self.bin = memoryview(blob)[start:end]
            offset = end + (-chunk_length % 4)
        if self.gltf is None:
            raise MeshFileError(f"{path}: no JSON chunk")

    def fail(self, what):
        raise MeshFileError(f"{self.path}: {what}")

    def _buffer(self, index):
        buffers = self.gltf.get("buffers", [])
        if index >= len(buffers):
            self.fail(f"buffer {index} does not exist")
        if "uri" in buffers[index]:
            self.fail(f"buffer {index} is external ('{buffers[index]['uri'][:40]}'): "
                      "expected the glb's binary chunk (mudcrack writes self-contained .glb)")
        return self.bin

    def accessor(self, index, want_float):
        """Accessor `index` as a flat array ('f' when want_float, else 'I'), and its width."""
        accessors = self.gltf.get("accessors", [])
        if not isinstance(index, int) or not 0 <= index < len(accessors):
            self.fail(f"accessor {index} does not exist")
        acc = accessors[index]
        where = f"accessor {index}"
        if "sparse" in acc:
            self.fail(f"{where}: sparse accessors are not supported")
        ctype, width, count = acc.get("componentType"), _WIDTH.get(acc.get("type")), acc.get("count", 0)
        if ctype not in _COMPONENT or width is None:
            self.fail(f"{where}: componentType {ctype} / type {acc.get('type')}: not a glTF 2.0 accessor")
        code, scale = _COMPONENT[ctype]
        size = struct.calcsize(code)
        if "bufferView" not in acc:  # all zeros, by the spec
            out = array(code, bytes(size * width * count))
        else:
            views = self.gltf.get("bufferViews", [])
            if not 0 <= acc["bufferView"] < len(views):
                self.fail(f"{where}: bufferView {acc['bufferView']} does not exist")
            view = views[acc["bufferView"]]
            data = self._buffer(view.get("buffer", 0))
            view_start = view.get("byteOffset", 0)
            view_end = view_start + view.get("byteLength", 0)
            if view_end > len(data):
                self.fail(f"{where}: its bufferView ends at byte {view_end} of a {len(data)}-byte buffer (truncated file?)")
            stride = view.get("byteStride", 0) or size * width
            start = view_start + acc.get("byteOffset", 0)
            end = start + stride * (count - 1) + size * width if count > 0 else start
            if end > view_end:
                self.fail(f"{where}: {count} elements run past the end of its bufferView (truncated file?)")
            if stride % size:
                self.fail(f"{where}: byteStride {stride} is not a multiple of the component size {size}")
            out = array(code)
            if stride == size * width:
                out.frombytes(data[start:end])  # tightly packed: one copy
            else:
                region = array(code)
                region.frombytes(data[start:start + stride * count] if start + stride * count <= len(data)
                                 else bytes(data[start:end]) + bytes(stride * count - (end - start)))
                step = stride // size
                out = array(code, bytes(size * width * count))
                for c in range(width):
                    out[c::width] = region[c::step][:count]
        if want_float and code != "f":
            out = array("f", (x / scale for x in out) if scale else out)
        elif not want_float and code not in ("B", "H", "I"):
            self.fail(f"{where}: indices of component type {ctype}: expected an unsigned integer type")
        elif not want_float and code != "I":
            out = array("I", out)
        return out, width

    def primitive(self, prim, where):
        if prim.get("mode", _MODE_TRIANGLES) != _MODE_TRIANGLES:
            self.fail(f"{where}: primitive mode {prim.get('mode')}: only triangles (4) are supported")
        attributes = prim.get("attributes", {})
        if "POSITION" not in attributes:
            self.fail(f"{where}: no POSITION attribute")
        out = MeshData()
        out.positions, width = self.accessor(attributes["POSITION"], True)
        if width != 3:
            self.fail(f"{where}: POSITION is not VEC3")
        n = out.vertex_count

        def attribute(name, widths):
            if name not in attributes:
                return None, None
            values, w = self.accessor(attributes[name], True)
            if w not in widths or len(values) != w * n:
                self.fail(f"{where}: {name}: {len(values) // max(w, 1)} elements of width {w}, "
                          f"expected {n} of width {' or '.join(map(str, widths))}")
            return values, w

        out.normals, _ = attribute("NORMAL", (3,))
        for name, slot in (("TEXCOORD_0", "uv0"), ("TEXCOORD_1", "uv1")):
            uv, _ = attribute(name, (2,))
            if uv is not None:
                # glTF's v points down the image; Blender's up
                uv[1::2] = array("f", (1.0 - v for v in uv[1::2]))
            setattr(out, slot, uv)
        colors, w = attribute("COLOR_0", (3, 4))
        if colors is not None and w == 3:
            rgba = array("f", bytes(4 * 4 * n))
            for c in range(3):
                rgba[c::4] = colors[c::3]
            rgba[3::4] = array("f", [1.0]) * n
            colors = rgba
        out.colors = colors
        if "indices" in prim:
            out.indices, w = self.accessor(prim["indices"], False)
            if w != 1:
                self.fail(f"{where}: indices are not SCALAR")
        else:
            out.indices = array("I", range(n))
        if len(out.indices) % 3:
            self.fail(f"{where}: {len(out.indices)} indices: not a whole number of triangles")
        if len(out.indices) and max(out.indices) >= n:
            self.fail(f"{where}: index {max(out.indices)} out of range ({n} vertices)")
        return out

    def meshes(self):
        """Every mesh instance of the default scene, node transforms applied, merged."""
        gltf = self.gltf
        nodes, meshes = gltf.get("nodes", []), gltf.get("meshes", [])
        scenes = gltf.get("scenes", [])
        if scenes:
            roots = scenes[gltf.get("scene", 0)].get("nodes", [])
        else:  # no scene: every node that is nobody's child
            children = {c for node in nodes for c in node.get("children", [])}
            roots = [i for i in range(len(nodes)) if i not in children]
        merged = MeshData()
        stack = [(r, _mat4_identity()) for r in reversed(roots)]
        seen = set()
        while stack:
            index, parent = stack.pop()
            if not isinstance(index, int) or not 0 <= index < len(nodes):
                self.fail(f"node {index} does not exist")
            if index in seen:
                self.fail(f"node {index} is reached twice (the node graph is not a tree)")
            seen.add(index)
            node = nodes[index]
            world = _mat4_mul(parent, _node_matrix(node))
            if "mesh" in node:
                if not 0 <= node["mesh"] < len(meshes):
                    self.fail(f"node {index}: mesh {node['mesh']} does not exist")
                for k, prim in enumerate(meshes[node["mesh"]].get("primitives", [])):
                    part = self.primitive(prim, f"mesh {node['mesh']} primitive {k}")
                    if not _is_identity(world):
                        _transform(part, world)
                    merged.append(part, self.path)
            stack.extend((c, world) for c in reversed(node.get("children", [])))
        return merged


def read_glb(path):
    """A .glb file's triangle meshes, merged (see the module's conventions)."""
    return _Glb(path).meshes()


# ---- obj (mc-surface --format obj: v/vt/vn, triangles, `o` per mesh) ----------------------------

def read_obj(path):
    """A Wavefront .obj file's triangles (polygons fanned), one vertex per distinct v/vt/vn
    corner. Vertex colours come from `v x y z r g b` lines (assimp writes them so) when every
    vertex has one; OBJ has no second UV channel (uv1 stays None: no fragment ids)."""
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise MeshFileError(f"{path}: cannot read: {e.strerror}") from None
    v, vt, vn, rgb = [], [], [], []
    corner_index = {}
    out = MeshData()
    uv0, normals, colors = array("f"), array("f"), array("f")
    has_uv = has_normal = None

    def resolve(token, lineno):
        nonlocal has_uv, has_normal
        parts = token.split("/")
        try:
            refs = [int(p) if p else 0 for p in parts] + [0] * (3 - len(parts))
        except ValueError:
            raise MeshFileError(f"{path}:{lineno}: bad face corner '{token}'") from None
        lists = (v, vt, vn)
        for k in range(3):
            if refs[k] < 0:
                refs[k] += len(lists[k]) + 1
            if refs[k] and not 1 <= refs[k] <= len(lists[k]) or (k == 0 and refs[0] == 0):
                raise MeshFileError(f"{path}:{lineno}: face corner '{token}' refers to a missing element")
        key = tuple(refs)
        index = corner_index.get(key)
        if index is None:
            index = corner_index[key] = len(corner_index)
            out.positions.extend(v[refs[0] - 1])
            if len(rgb) == len(v):
                colors.extend(rgb[refs[0] - 1])
            if has_uv is None:
                has_uv, has_normal = refs[1] != 0, refs[2] != 0
            if has_uv:
                uv0.extend(vt[refs[1] - 1] if refs[1] else (0.0, 0.0))
            if has_normal:
                normals.extend(vn[refs[2] - 1] if refs[2] else (0.0, 0.0, 1.0))
        return index

    for lineno, line in enumerate(lines, 1):
        fields = line.split()
        if not fields:
            continue
        tag = fields[0]
        try:
            if tag == "v":
                if len(fields) < 4:
                    raise ValueError
                v.append(tuple(float(x) for x in fields[1:4]))
                if len(fields) >= 7:
                    rgb.append((float(fields[4]), float(fields[5]), float(fields[6]), 1.0))
            elif tag == "vt":
                vt.append((float(fields[1]), float(fields[2]) if len(fields) > 2 else 0.0))
            elif tag == "vn":
                vn.append(tuple(float(x) for x in fields[1:4]))
            elif tag == "f":
                corners = [resolve(t, lineno) for t in fields[1:]]
                if len(corners) < 3:
                    raise MeshFileError(f"{path}:{lineno}: a face with {len(corners)} corners")
                for k in range(1, len(corners) - 1):
                    out.indices.extend((corners[0], corners[k], corners[k + 1]))
        except (ValueError, IndexError):
            raise MeshFileError(f"{path}:{lineno}: cannot parse '{line.strip()[:60]}'") from None
    out.uv0 = uv0 if has_uv else None
    out.normals = normals if has_normal else None
    out.colors = colors if v and len(rgb) == len(v) and len(colors) == 4 * out.vertex_count else None
    return out
