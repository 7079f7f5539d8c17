# The materials the importer gives its objects: water (Principled BSDF, transmission 1,
# IOR 1.33, a cyan absorption inside (4/m); shadow rays pass straight through, so the floor under
# the water is lit without caustics, which a path tracer finds only with many samples), cloth (a matte fabric), rigid bodies (a grey satin), the fluid's density as a
# volume (Principled Volume reading the "density" grid) and the particles' points.
import bpy

WATER_IOR = 1.33


def principled(name):
    """A new node material with a Principled BSDF wired to its output: (material, bsdf, output)."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes = m.node_tree.nodes
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None) or nodes.new("ShaderNodeOutputMaterial")
    if bsdf is None:  # some builds start a node material empty
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
        m.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    return m, bsdf, output


def water():
    m, bsdf, output = principled("Seiche water")
    bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.02
    bsdf.inputs["Transmission"].default_value = 1.0
    bsdf.inputs["IOR"].default_value = WATER_IOR
    nodes, links = m.node_tree.nodes, m.node_tree.links
    light_path = nodes.new("ShaderNodeLightPath")
    transparent = nodes.new("ShaderNodeBsdfTransparent")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(light_path.outputs["Is Shadow Ray"], mix.inputs["Fac"])
    links.new(bsdf.outputs["BSDF"], mix.inputs[1])
    links.new(transparent.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    absorption = nodes.new("ShaderNodeVolumeAbsorption")
    absorption.inputs["Color"].default_value = (0.55, 0.8, 0.9, 1.0)
    absorption.inputs["Density"].default_value = 4.0  # 1/m: a block 0.5 m deep turns cyan
    links.new(absorption.outputs["Volume"], output.inputs["Volume"])
    for k, n in enumerate((light_path, transparent, absorption)):
        n.location = (bsdf.location.x, bsdf.location.y + 300 + 200 * k)
    mix.location = (output.location.x - 200, output.location.y)
    m.diffuse_color = (0.55, 0.75, 0.95, 0.5)  # the viewport's solid colour
    m.use_screen_refraction = True  # Eevee: refraction (with the scene's screen space refraction)
    m.blend_method = "HASHED"
    return m


def _opaque(name, colour, roughness):
    """A Principled BSDF of `colour` (RGBA) and `roughness`; the viewport shows the same colour."""
    m, bsdf, _ = principled(name)
    bsdf.inputs["Base Color"].default_value = colour
    bsdf.inputs["Roughness"].default_value = roughness
    m.diffuse_color = colour
    return m


def cloth(name):
    return _opaque(f"Seiche cloth {name}", (0.75, 0.22, 0.16, 1.0), 0.8)


def body(name):
    return _opaque(f"Seiche body {name}", (0.55, 0.55, 0.6, 1.0), 0.5)


def particles():
    return _opaque("Seiche particles", (0.1, 0.35, 0.8, 1.0), 0.3)


def density_volume():
    m = bpy.data.materials.new("Seiche density")
    m.use_nodes = True
    nodes = m.node_tree.nodes
    for n in list(nodes):
        if n.type != "OUTPUT_MATERIAL":
            nodes.remove(n)
    output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None) or nodes.new("ShaderNodeOutputMaterial")
    volume = nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Color"].default_value = (0.6, 0.8, 0.95, 1.0)
    volume.inputs["Density"].default_value = 5.0
    if "Density Attribute" in volume.inputs:
        volume.inputs["Density Attribute"].default_value = "density"
    m.node_tree.links.new(volume.outputs["Volume"], output.inputs["Volume"])
    return m
