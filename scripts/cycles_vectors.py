"""A real Cycles render to check `shutter vectors` against (issue 32): three frames of two
textured planes on accelerating paths (so backward and forward motion differ, and both axes
move) before a textured wall, written as Blender writes a multi-layer EXR
(ViewLayer.Combined.RGBA, ViewLayer.Depth.Z, ViewLayer.Vector.XYZW).

    python -m venv target/bpy && target/bpy/bin/pip install bpy==5.2.3   # ~400 MB, once
    target/bpy/bin/python scripts/cycles_vectors.py OUT_DIR [WIDTH HEIGHT SAMPLES [DEPTH]]
    shutter vectors --preset blender --color 'OUT_DIR/shot.####.exr'

Motion blur is off (the vectors come with a sharp beauty, as a render for post blur is made).
"""

import sys

import bpy


def main():
    out = sys.argv[1]
    width = int(sys.argv[2]) if len(sys.argv) > 2 else 320
    height = int(sys.argv[3]) if len(sys.argv) > 3 else 180
    samples = int(sys.argv[4]) if len(sys.argv) > 4 else 16
    # "32" (float) or "16" (half, as the shipped fixture fixtures/cycles is written).
    depth = sys.argv[5] if len(sys.argv) > 5 else "32"

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.render.use_motion_blur = False
    scene.render.film_transparent = False
    scene.frame_start, scene.frame_end = 1, 3
    layer = scene.view_layers[0]
    layer.name = "ViewLayer"
    layer.use_pass_z = True
    layer.use_pass_vector = True
    settings = scene.render.image_settings
    # Blender 5 picks the multi-layer media type first, then its one format.
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = depth
    settings.exr_codec = "ZIP"
    scene.render.filepath = f"{out}/shot.####"

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs[1].default_value = 1.0
    scene.world = world

    def textured(name, scale, seed_offset):
        material = bpy.data.materials.new(name)
        material.use_nodes = True
        nodes, links = material.node_tree.nodes, material.node_tree.links
        emission = nodes.new("ShaderNodeEmission")
        noise = nodes.new("ShaderNodeTexNoise")
        noise.noise_dimensions = "4D"
        noise.inputs["Scale"].default_value = scale
        noise.inputs["Detail"].default_value = 8.0
        noise.inputs["W"].default_value = seed_offset
        links.new(noise.outputs["Color"], emission.inputs["Color"])
        output = nodes["Material Output"]
        links.new(emission.outputs["Emission"], output.inputs["Surface"])
        return material

    def plane(name, size, location, material):
        bpy.ops.mesh.primitive_plane_add(size=size, location=location)
        obj = bpy.context.active_object
        obj.name = name
        obj.data.materials.append(material)
        return obj

    plane("wall", 40.0, (0.0, 0.0, -6.0), textured("wall", 6.0, 0.3))
    near = plane("near", 3.0, (0.0, 0.0, 0.0), textured("near", 9.0, 1.7))
    far = plane("far", 5.0, (0.0, 0.0, -3.0), textured("far", 7.0, 2.9))
    # Accelerating paths, in world units per frame (the camera sees about 10 units across).
    for frame in (1, 2, 3):
        t = frame - 2
        near.location = (-1.0 + 0.45 * t + 0.12 * t * t, 0.3 - 0.25 * t + 0.1 * t * t, 0.0)
        near.keyframe_insert("location", frame=frame)
        far.location = (1.5 - 0.35 * t + 0.08 * t * t, -0.5 + 0.3 * t + 0.09 * t * t, -3.0)
        far.keyframe_insert("location", frame=frame)
    camera_data = bpy.data.cameras.new("camera")
    camera_data.lens = 35.0
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = (0.0, 0.0, 10.0)
    scene.collection.objects.link(camera)
    scene.camera = camera

    bpy.ops.render.render(animation=True)


main()
