"""How the debris object shows: a Geometry Nodes modifier "mudcrack debris points" that turns its
vertices into points of radius "pscale" (Mesh to Points).

Why: Blender draws a mesh's loose vertices in Edit Mode only, so a debris object of bare vertices
would be invisible in the viewport and in a render. As points it shows as grains of the right
size in both (Cycles renders points as spheres), and its attributes (velocity, id, piece) pass
through. A TD who wants pebbles puts Instance on Points after the group's input instead (Scale:
Named Attribute "pscale"); the object's mesh itself, what the playback swaps each frame, stays
the vertices with their attributes.

Blender API: 4.0 moved a node group's sockets to `interface.new_socket`; 3.x has
`inputs.new`/`outputs.new`. Named Attribute has one "Attribute" output per data type in 3.x (the
one of the chosen type is enabled), a single one in 4.x.
"""
import bpy

__all__ = ["DEBRIS_MODIFIER", "add_debris_points_modifier"]

DEBRIS_MODIFIER = "mudcrack debris points"
_GROUP = "mudcrack debris points"


def _add_geometry_socket(group, in_out):
    if hasattr(group, "interface"):  # 4.0+
        group.interface.new_socket("Geometry", in_out=in_out, socket_type="NodeSocketGeometry")
    else:
        (group.inputs if in_out == "INPUT" else group.outputs).new("NodeSocketGeometry", "Geometry")


def _build_group():
    group = bpy.data.node_groups.new(_GROUP, "GeometryNodeTree")
    _add_geometry_socket(group, "INPUT")
    _add_geometry_socket(group, "OUTPUT")
    nodes, links = group.nodes, group.links
    group_in, group_out = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    group_in.location, group_out.location = (-400, 0), (300, 0)
    pscale = nodes.new("GeometryNodeInputNamedAttribute")
    pscale.data_type = "FLOAT"
    pscale.inputs["Name"].default_value = "pscale"
    pscale.location = (-400, -150)
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.mode = "VERTICES"
    to_points.location = (0, 0)
    radius = next(o for o in pscale.outputs if o.name == "Attribute" and o.enabled)
    links.new(group_in.outputs[0], to_points.inputs["Mesh"])
    links.new(radius, to_points.inputs["Radius"])
    links.new(to_points.outputs["Points"], group_out.inputs[0])
    return group


def add_debris_points_modifier(obj):
    """Gives the debris object the modifier (the node group is made once per file)."""
    group = bpy.data.node_groups.get(_GROUP) or _build_group()
    modifier = obj.modifiers.new(DEBRIS_MODIFIER, "NODES")
    modifier.node_group = group
    return modifier
