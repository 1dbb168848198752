"""The two shaders of a mudcrack shot, "mudcrack soil" (boundary) and "mudcrack crack", shading
the vertex colors mudcrack writes: COLOR_0 = (saturation, logistic(alpha), 0, 1).

The node graph mirrors mc-render's moisture mode (render/colormap.h, render/renderer.cpp):
    base color = albedo * (1 - 0.55 saturation)            wet soil is darker
    crack:       albedo * (0.62, 0.50, 0.42) * (...)       crack interiors darker and warmer
    roughness  = 0.9 - 0.5 saturation                       wet soil is glossier
and mc-render's hardening mode as a switch: the "hardening view" value node (0: moisture look,
1: the coolwarm colormap of logistic(alpha), blue = softened, red = hardened, 0.5 = alpha 0).
Everything goes through a Principled BSDF, so Cycles and Eevee render it with no node work.

Blender API: ShaderNodeVertexColor (the "Color Attribute" node), ShaderNodeSeparateColor and
ShaderNodeMix exist from 3.4 (the first two from 3.3) and in 4.x; the Principled BSDF's "Base
Color" and "Roughness" inputs keep their names in 4.x (its "Specular" input does not, so it is
left alone).
"""
import bpy

__all__ = ["COLOR_ATTRIBUTE", "ALBEDO", "CRACK_TINT", "MOISTURE_DARKENING", "material_for"]

COLOR_ATTRIBUTE = "Col"           # the mesh color attribute the playback writes COLOR_0 into
ALBEDO = (0.55, 0.42, 0.30)        # dry soil, linear RGB (render/render_params.h)
CRACK_TINT = (0.62, 0.50, 0.42)    # render/renderer.cpp kCrackTint
MOISTURE_DARKENING = 0.55          # render/colormap.h kMoistureDarkening
# render/colormap.cpp: Moreland's coolwarm, 9 stops, 8-bit sRGB
_COOLWARM = ((59, 76, 192), (98, 130, 234), (141, 176, 254), (184, 208, 249), (221, 221, 221),
             (245, 196, 173), (244, 154, 123), (222, 96, 77), (180, 4, 38))
MATERIAL_TAG = "mudcrack_material"  # custom property: "boundary" or "crack"


def _srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def _socket(sockets, identifier):
    for s in sockets:
        if s.identifier == identifier:
            return s
    raise KeyError(identifier)


def _build(mat, kind):
    mat.use_nodes = True
    tree = mat.node_tree
    nodes, links = tree.nodes, tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    out.location = (900, 0)
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (600, 0)
    links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])

    # vertex colors: r = saturation, g = logistic(alpha)
    attr = nodes.new("ShaderNodeVertexColor")
    attr.name = attr.label = "mudcrack vertex color"
    attr.layer_name = COLOR_ATTRIBUTE
    attr.location = (-900, 0)
    sep = nodes.new("ShaderNodeSeparateColor")
    sep.mode = "RGB"
    sep.location = (-700, 0)
    links.new(attr.outputs["Color"], sep.inputs["Color"])
    saturation, hardening = sep.outputs[0], sep.outputs[1]

    # moisture: albedo (1 - k s), the crack's albedo tinted darker
    darkening = nodes.new("ShaderNodeMath")
    darkening.name = darkening.label = "mudcrack moisture darkening"
    darkening.operation = "MULTIPLY_ADD"
    darkening.use_clamp = True
    darkening.inputs[1].default_value = -MOISTURE_DARKENING
    darkening.inputs[2].default_value = 1.0
    darkening.location = (-450, 150)
    links.new(saturation, darkening.inputs[0])
    albedo = nodes.new("ShaderNodeVectorMath")
    albedo.name = albedo.label = "mudcrack albedo"
    albedo.operation = "SCALE"
    tint = CRACK_TINT if kind == "crack" else (1.0, 1.0, 1.0)
    albedo.inputs[0].default_value = tuple(a * t for a, t in zip(ALBEDO, tint))
    albedo.location = (-200, 150)
    links.new(darkening.outputs[0], _socket(albedo.inputs, "Scale"))

    # hardening: coolwarm(logistic(alpha)), shown when "hardening view" is 1
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.name = ramp.label = "mudcrack hardening colormap"
    ramp.location = (-450, -150)
    elements = ramp.color_ramp.elements
    while len(elements) > 1:
        elements.remove(elements[-1])
    for i, rgb in enumerate(_COOLWARM):
        e = elements[0] if i == 0 else elements.new(i / (len(_COOLWARM) - 1))
        e.position = i / (len(_COOLWARM) - 1)
        e.color = tuple(_srgb_to_linear(c / 255.0) for c in rgb) + (1.0,)
    links.new(hardening, ramp.inputs["Fac"])
    view = nodes.new("ShaderNodeValue")
    view.name = view.label = "hardening view"
    view.outputs[0].default_value = 0.0
    view.location = (-200, -350)
    mix = nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    mix.clamp_factor = True
    mix.location = (150, 0)
    links.new(view.outputs[0], _socket(mix.inputs, "Factor_Float"))
    links.new(albedo.outputs["Vector"], _socket(mix.inputs, "A_Color"))
    links.new(ramp.outputs["Color"], _socket(mix.inputs, "B_Color"))
    links.new(_socket(mix.outputs, "Result_Color"), bsdf.inputs["Base Color"])

    # wet soil is glossier
    rough = nodes.new("ShaderNodeMath")
    rough.name = rough.label = "mudcrack wet roughness"
    rough.operation = "MULTIPLY_ADD"
    rough.use_clamp = True
    rough.inputs[1].default_value = -0.5
    rough.inputs[2].default_value = 0.9
    rough.location = (150, -250)
    links.new(saturation, rough.inputs[0])
    links.new(rough.outputs[0], bsdf.inputs["Roughness"])

    # the viewport's solid mode shows the dry color
    mat.diffuse_color = tuple(a * t for a, t in zip(ALBEDO, tint)) + (1.0,)
    mat.roughness = 0.9


def material_for(kind):
    """The shared material of a kind ("boundary" or "crack"), created on first use; an existing
    one (an artist may have edited it) is kept as it is."""
    name = "mudcrack crack" if kind == "crack" else "mudcrack soil"
    for mat in bpy.data.materials:
        if mat.get(MATERIAL_TAG) == kind and mat.name.startswith(name):
            return mat
    mat = bpy.data.materials.new(name)
    mat[MATERIAL_TAG] = kind
    _build(mat, kind)
    return mat
