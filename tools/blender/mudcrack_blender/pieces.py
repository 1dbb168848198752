"""Separating a frame's pieces into objects: "Object > Separate mudcrack pieces".

The playback objects change their mesh every frame, so a piece cannot be an object of its own
there (pieces appear when a crack splits one, and an object per piece per frame would be
thousands of objects). Their faces carry the piece id instead (the face attribute "piece"), which
Geometry Nodes reads per frame. For hand work on a piece (a hero plate to sculpt, shade or hand
to a rigid-body setup), this operator snapshots the frame on screen: one static object
`piece_<id>` per piece, holding that piece's boundary faces (material "mudcrack soil") and its
crack walls (material "mudcrack crack") with their UVs, colors and normals, parented to the
shot's root (so they sit where the playback shows them) in a collection "<shot> pieces.<frame>".

The meshes are built again from the frame's files (the path each playback mesh keeps in its
"mudcrack_file" property), through the same reader and builder as the playback: a piece object
is exactly the playback's faces of that piece.
"""
from array import array

import bpy

from .materials import material_for
from .meshfile import MeshData, read_mesh_file
from .playback import PROP_FILE, PROP_KIND, build_mesh, face_pieces
from .shot import KINDS

__all__ = ["PIECE_PREFIX", "split_by_piece", "separate_pieces"]

PIECE_PREFIX = "piece_"
PROP_PIECE = "mudcrack_piece"  # object: the piece id of a separated piece


def split_by_piece(data):
    """{piece id: MeshData of that piece's triangles} of MeshData with fragment ids (UV channel
    1); its vertices renumbered in first-use order. {} when the data has no fragment ids."""
    pieces = face_pieces(data)
    if pieces is None:
        return {}
    faces_of = {}
    for f, piece in enumerate(pieces):
        faces_of.setdefault(piece, []).append(f)
    return {piece: _subset(data, faces) for piece, faces in sorted(faces_of.items())}


def _subset(data, faces):
    """MeshData of the triangles `faces` of `data`, keeping only the vertices they use."""
    out = MeshData()
    new_index = {}
    corners = data.indices
    for f in faces:
        for v in corners[3 * f:3 * f + 3]:
            out.indices.append(new_index.setdefault(v, len(new_index)))
    used = list(new_index)  # old vertex ids in their new order (dicts keep insertion order)
    out.positions = _gather(data.positions, used, 3)
    for name, width in (("normals", 3), ("uv0", 2), ("uv1", 2), ("colors", 4)):
        values = getattr(data, name)
        setattr(out, name, None if values is None else _gather(values, used, width))
    return out


def _gather(values, vertices, width):
    out = array(values.typecode)
    for v in vertices:
        out.extend(values[width * v:width * v + width])
    return out


def _frame_files(objects):
    """{kind: file} of the files the playback objects show now ("" meshes: nothing shown)."""
    return {obj[PROP_KIND]: obj.data.get(PROP_FILE) for obj in objects if obj.data.get(PROP_FILE)}


def _piece_mesh(name, boundary, crack):
    """One mesh of a piece's boundary and crack MeshData (either may be None): the boundary's
    faces with the soil material (slot 0), then the crack's with the crack material (slot 1)."""
    parts = [(kind, d) for kind, d in (("boundary", boundary), ("crack", crack)) if d is not None]
    # counted first: appending to an empty MeshData takes over the first part's arrays
    slots = array("i")
    for slot, (_, d) in enumerate(parts):
        slots.extend(array("i", [slot]) * d.face_count)
    merged = MeshData()
    for _, d in parts:
        merged.append(d, name)
    me = build_mesh(name, merged, parts[0][0])
    if len(parts) == 2:
        me.materials.append(material_for("crack"))
        me.polygons.foreach_set("material_index", slots)
        me.update()
    return me


def separate_pieces(context, objects, frame):
    """Snapshots the pieces of a shot's playback objects ({kind: object}, as import_shot returns)
    at their current frame `frame`: one object `piece_<id>` per piece (see the module's doc).
    Returns (collection, [objects]); no objects when the frame's meshes carry no piece ids."""
    files = _frame_files(objects.values())
    by_kind = {kind: split_by_piece(read_mesh_file(path)) for kind, path in files.items() if kind in KINDS}
    ids = sorted(set().union(*by_kind.values())) if by_kind else []
    root = next(iter(objects.values())).parent
    shot_name = root.name if root is not None else "mudcrack"
    collection = bpy.data.collections.new(f"{shot_name} pieces.{frame:04d}")
    context.scene.collection.children.link(collection)
    made = []
    for piece in ids:
        name = f"{PIECE_PREFIX}{piece}"
        me = _piece_mesh(name, by_kind.get("boundary", {}).get(piece), by_kind.get("crack", {}).get(piece))
        obj = bpy.data.objects.new(name, me)
        obj[PROP_PIECE] = piece
        obj["mudcrack_frame"] = frame
        obj.parent = root
        collection.objects.link(obj)
        made.append(obj)
    return collection, made
