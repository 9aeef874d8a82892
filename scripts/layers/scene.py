"""A real Cycles render with view layers (issue 33). --scene fan (the default): a fan spinning
and a cube flying sideways (collection FG) in front of a textured wall and three boxes
(collection BG), the camera trucking left, so the foreground uncovers background during the
exposure. --scene gear-spin and gear-slide, the opposite case: a ten-toothed gear (FG) before
the same wall (BG), the camera still. The gear turns in place, its rim sliding along itself
(the tips' arcs keep to their own path; only the flanks cover and uncover wall, in the gaps
between the teeth), or slides sideways, the same rim moving across itself (its leading side
covers the wall, its trailing side uncovers it).

    python scene.py OUT KIND [--scene fan|gear-spin|gear-slide] [--others holdout|exclude|indirect]
                            [--size WxH] [--samples N] [--seed S] [--frames A-B] [--name NAME]
                            [--camera truck|pan|still]

KIND, each written as Blender writes an OpenEXR MultiLayer file (one part per pass, channels
`<ViewLayer>.Combined.RGBA`, `.Depth.Z`, `.Vector.XYZW`), 32-bit float, ZIP:
  layers         OUT/layers.####.exr: view layers FG (the BG collection in it as --others
                 says) and BG (FG excluded), motion blur off, Combined, Z and Vector
  fg             OUT/fg_OTHERS.####.exr: view layer FG alone, the same (to compare what
                 excluding BG, holding it out or making it indirect-only writes)
  single         OUT/single.####.exr: one view layer `ViewLayer` with everything, the same
  reference      OUT/reference.####.exr: `ViewLayer` with Cycles' motion blur (shutter 0.5,
                 Center on Frame: shutter's defaults), Combined and Z
  reference_fg   OUT/reference_fg.####.exr: view layer FG alone with motion blur, as
                 `reference` (to score the FG layer's blur alone, alpha included)
  reference_dof  OUT/reference_dof.####.exr: `ViewLayer`, the lens's depth of field, no
                 motion blur

--camera pan turns the camera about its vertical axis (PAN_SPIN degrees a frame) where the
fan's camera trucks by default: every surface's motion then a smooth field across the frame
(perspective makes it faster towards the sides) with no parallax between the wall and the
boxes. The gears' camera is still by default, so that only the gear moves.

Everything is emission-shaded (no lights, no bounces): the only noise is the pixel filter's,
the shutter's and the lens's sampling. Denoiser off, adaptive sampling off, fixed seed.
Units are metres: the lens (LENS below) is the one to give `shutter dof`.
"""

import argparse
import math

import bpy  # first: bmesh and mathutils come with it
import bmesh  # noqa: E402
from mathutils import Matrix  # noqa: E402

# The camera: 35 mm on a 36 mm-wide sensor (horizontal fit), focused on the cube's path.
LENS = {"focal_length": 35.0, "sensor_width": 36.0, "f_stop": 1.4, "focus_distance": 0.8}
SHUTTER = 0.5
CAMERA_Z = 1.0
# Metres per frame: the camera trucks left, the cube flies right; degrees per frame.
CAMERA_SPEED = -0.025
CUBE_SPEED = 0.06
# Degrees per frame the camera turns with --camera pan.
PAN_SPIN = 1.5
FAN_SPIN = 40.0
# The gear, 0.6 m away (about 780 px a metre there): radii in metres; degrees a frame turning
# in place (45 px on the tips); metres a frame sliding right (20 px, a little under a tooth's
# width).
GEAR_OUTER = 0.11
GEAR_ROOT = 0.085
GEAR_TEETH = 10
GEAR_SPIN = 30.0
GEAR_SLIDE = 0.026
# Turned off square, so that no flank of the sliding gear lies along the scanlines.
GEAR_SLIDE_ANGLE = 7.0
SCENES = ("fan", "gear-spin", "gear-slide")
# Keys from frame -2 to 6: frames 1 to 5 have their neighbours (the Vector pass) keyed too.
KEY_FRAMES = range(-2, 7)


def arguments():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument(
        "kind", choices=["layers", "fg", "single", "reference", "reference_fg", "reference_dof"]
    )
    p.add_argument(
        "--others",
        choices=["holdout", "exclude", "indirect"],
        default="holdout",
        help="what the BG collection is in view layer FG",
    )
    p.add_argument("--size", default="480x270")
    p.add_argument("--samples", type=int, default=128)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--frames", default="1-1")
    p.add_argument("--name", help="file name before .####.exr (default: KIND, fg_OTHERS)")
    p.add_argument("--scene", choices=SCENES, default="fan")
    p.add_argument(
        "--camera",
        choices=["truck", "pan", "still"],
        help="how the camera moves (default: truck for the fan, still for the gears)",
    )
    return p.parse_args()


def emission(name, build):
    """A material whose surface is an Emission shader fed by build(nodes, links) -> socket."""
    material = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):  # 5.x materials always have their node tree
        material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    for node in list(nodes):
        if node.type != "OUTPUT_MATERIAL":
            nodes.remove(node)
    shader = nodes.new("ShaderNodeEmission")
    links.new(build(nodes, links), shader.inputs["Color"])
    links.new(shader.outputs["Emission"], nodes["Material Output"].inputs["Surface"])
    return material


def checker(c1, c2, scale, noise_scale, w):
    """A checker whose squares are shaded by a noise, so each square has detail."""

    def build(nodes, links):
        check = nodes.new("ShaderNodeTexChecker")
        check.inputs["Color1"].default_value = (*c1, 1.0)
        check.inputs["Color2"].default_value = (*c2, 1.0)
        check.inputs["Scale"].default_value = scale
        noise = nodes.new("ShaderNodeTexNoise")
        noise.noise_dimensions = "4D"
        noise.inputs["Scale"].default_value = noise_scale
        noise.inputs["Detail"].default_value = 6.0
        noise.inputs["W"].default_value = w
        mix = nodes.new("ShaderNodeMix")
        mix.data_type = "RGBA"
        mix.blend_type = "MULTIPLY"
        mix.inputs["Factor"].default_value = 0.7
        links.new(check.outputs["Color"], mix.inputs["A"])
        links.new(noise.outputs["Color"], mix.inputs["B"])
        return mix.outputs["Result"]

    return build


def noise(scale, w):
    def build(nodes, links):
        tex = nodes.new("ShaderNodeTexNoise")
        tex.noise_dimensions = "4D"
        tex.inputs["Scale"].default_value = scale
        tex.inputs["Detail"].default_value = 8.0
        tex.inputs["W"].default_value = w
        return tex.outputs["Color"]

    return build


def stripes(c1, c2, scale):
    def build(nodes, links):
        wave = nodes.new("ShaderNodeTexWave")
        wave.inputs["Scale"].default_value = scale
        wave.inputs["Distortion"].default_value = 2.0
        ramp = nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (*c1, 1.0)
        ramp.color_ramp.elements[1].color = (*c2, 1.0)
        links.new(wave.outputs["Fac"], ramp.inputs["Fac"])
        return ramp.outputs["Color"]

    return build


def mesh_object(name, collection, material, fill):
    """An object whose mesh fill(bm) builds, with generated texture coordinates."""
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    fill(bm)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def box(sx, sy, sz, offset=(0.0, 0.0, 0.0), angle=0.0):
    def fill(bm):
        matrix = (
            Matrix.Rotation(angle, 4, "Z")
            @ Matrix.Translation(offset)
            @ Matrix.Diagonal((sx, sy, sz, 1.0))
        )
        bmesh.ops.create_cube(bm, size=1.0, matrix=matrix)

    return fill


def fan_fill(radius, width, thickness, blades):
    """A hub and `blades` blades in the XY plane, spinning about Z."""

    def fill(bm):
        for i in range(blades):
            angle = 2.0 * math.pi * i / blades
            matrix = (
                Matrix.Rotation(angle, 4, "Z")
                @ Matrix.Translation((radius / 2.0, 0.0, 0.0))
                @ Matrix.Rotation(0.25, 4, "X")
                @ Matrix.Diagonal((radius, width, thickness, 1.0))
            )
            bmesh.ops.create_cube(bm, size=1.0, matrix=matrix)
        hub = Matrix.Diagonal((0.3 * radius, 0.3 * radius, 2.0 * thickness, 1.0))
        bmesh.ops.create_cube(bm, size=1.0, matrix=hub)

    return fill


def gear_fill(outer, root, thickness, teeth, tip=0.45, base=0.6):
    """A gear in the XY plane, `thickness` deep along Z: `teeth` teeth whose tips span `tip` of
    a tooth's period on the outer circle and whose bases span `base` of it on the root circle
    (slanted flanks, as a spur gear's)."""

    def fill(bm):
        period = 2.0 * math.pi / teeth
        # Six segments an arc: at 0.6 m a tip's straight chords stay within a tenth of a pixel
        # of the circle.
        arc = 6
        points = []
        for i in range(teeth):
            centre = i * period
            t0, t1 = centre - tip * period / 2, centre + tip * period / 2
            b1, next_b0 = centre + base * period / 2, centre + period - base * period / 2
            for k in range(arc + 1):
                a = t0 + (t1 - t0) * k / arc
                points.append((outer * math.cos(a), outer * math.sin(a)))
            for k in range(arc + 1):
                a = b1 + (next_b0 - b1) * k / arc
                points.append((root * math.cos(a), root * math.sin(a)))
        face = bm.faces.new([bm.verts.new((x, y, -thickness / 2)) for x, y in points])
        extruded = bmesh.ops.extrude_face_region(bm, geom=[face])["geom"]
        moved = [v for v in extruded if isinstance(v, bmesh.types.BMVert)]
        bmesh.ops.translate(bm, verts=moved, vec=(0.0, 0.0, thickness))
        bmesh.ops.recalc_face_normals(bm, faces=bm.faces[:])
        # The caps are concave polygons of 140 corners: triangles here, so that no renderer
        # has a polygon of its own to split.
        bmesh.ops.triangulate(bm, faces=bm.faces[:])

    return fill


def setup(width, height):
    """An empty Cycles scene writing float multilayer EXR, with collections FG and BG."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    # Keys with linear interpolation: constant speeds, so Cycles' shutter (which interpolates
    # each object's transform between its motion steps) and the Vector pass (frames -1, +1)
    # see the same motion.
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_animated_seed = False
    scene.cycles.max_bounces = 0
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"

    fg = bpy.data.collections.new("FG")
    bg = bpy.data.collections.new("BG")
    scene.collection.children.link(fg)
    scene.collection.children.link(bg)
    return scene, fg, bg


def wall(bg):
    """Every scene's backdrop: a checkered wall 1.8 m from the camera."""
    obj = mesh_object(
        "wall",
        bg,
        emission("wall", checker((0.85, 0.8, 0.65), (0.12, 0.18, 0.3), 40.0, 6.0, 0.3)),
        box(4.0, 3.0, 0.01),
    )
    obj.location = (0.0, 0.0, -0.8)


def fan_scene(fg, bg):
    """The fan's scene before the wall: three boxes (BG), the fan and the cube (FG)."""
    # The boxes give the background parallax of its own as the camera trucks.
    boxes = [
        ((-0.45, 0.12, -0.35), (0.22, 0.16, 0.1), noise(5.0, 1.1)),
        ((0.05, -0.18, -0.45), (0.28, 0.14, 0.1), noise(7.0, 2.3)),
        ((0.42, 0.16, -0.3), (0.16, 0.26, 0.1), noise(9.0, 3.7)),
    ]
    for i, (location, size, tex) in enumerate(boxes):
        obj = mesh_object(f"box{i}", bg, emission(f"box{i}", tex), box(*size))
        obj.location = location
        obj.rotation_euler = (0.3, -0.2, 0.4 * i)

    # Foreground: a four-bladed fan 0.6 m away and a cube 0.8 m away flying right.
    fan = mesh_object(
        "fan",
        fg,
        emission("fan", stripes((0.9, 0.25, 0.05), (1.0, 0.85, 0.2), 3.0)),
        fan_fill(0.1, 0.035, 0.006, 4),
    )
    cube = mesh_object(
        "cube",
        fg,
        emission("cube", checker((0.2, 0.9, 0.3), (0.95, 0.95, 0.9), 4.0, 12.0, 5.1)),
        box(0.11, 0.11, 0.11),
    )
    fan.location = (-0.12, 0.03, 0.4)
    for frame in KEY_FRAMES:
        t = frame - 1
        # The tilted fan turns about the world's Z, the camera's axis: circular screen paths.
        fan.rotation_euler = (0.15, -0.1, math.radians(FAN_SPIN * t))
        fan.keyframe_insert("rotation_euler", frame=frame)
        cube.location = (0.1 + CUBE_SPEED * t, -0.04, 0.2)
        cube.rotation_euler = (0.5, 0.35, math.radians(8.0 * t))
        cube.keyframe_insert("location", frame=frame)
        cube.keyframe_insert("rotation_euler", frame=frame)


def gear(fg, motion):
    """The gear 0.6 m away, square to the view axis and centred on it at frame 1: turning about
    that axis (`spin`) or sliding right (`slide`)."""
    obj = mesh_object(
        "gear",
        fg,
        emission("gear", checker((0.9, 0.35, 0.08), (1.0, 0.9, 0.35), 6.0, 14.0, 2.2)),
        gear_fill(GEAR_OUTER, GEAR_ROOT, 0.01, GEAR_TEETH),
    )
    for frame in KEY_FRAMES:
        t = frame - 1
        if motion == "spin":
            obj.location = (0.0, 0.0, 0.4)
            obj.rotation_euler = (0.0, 0.0, math.radians(GEAR_SPIN * t))
            obj.keyframe_insert("rotation_euler", frame=frame)
        else:
            obj.location = (GEAR_SLIDE * t, 0.0, 0.4)
            obj.rotation_euler = (0.0, 0.0, math.radians(GEAR_SLIDE_ANGLE))
        obj.keyframe_insert("location", frame=frame)


def camera(scene, motion):
    """The camera CAMERA_Z above the origin looking down -Z, LENS's lens, its depth of field
    off (a kind turns it on); `motion` truck, pan or still."""
    data = bpy.data.cameras.new("camera")
    data.lens = LENS["focal_length"]
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = LENS["sensor_width"]
    data.dof.focus_distance = LENS["focus_distance"]
    data.dof.aperture_fstop = LENS["f_stop"]
    data.dof.aperture_blades = 0
    data.dof.use_dof = False
    obj = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(obj)
    scene.camera = obj
    for frame in KEY_FRAMES:
        if motion == "pan":
            obj.location = (0.0, 0.0, CAMERA_Z)
            obj.rotation_euler = (0.0, math.radians(PAN_SPIN * (frame - 1)), 0.0)
            obj.keyframe_insert("rotation_euler", frame=frame)
        elif motion == "truck":
            obj.location = (CAMERA_SPEED * (frame - 1), 0.0, CAMERA_Z)
        else:
            obj.location = (0.0, 0.0, CAMERA_Z)
        obj.keyframe_insert("location", frame=frame)


def view_layers(scene):
    """Three view layers: everything, the foreground alone, the background alone."""
    everything = scene.view_layers[0]
    everything.name = "ViewLayer"
    layers = {"ViewLayer": everything}
    for name, drop in (("FG", "BG"), ("BG", "FG")):
        layer = scene.view_layers.new(name)
        layer.layer_collection.children[drop].exclude = True
        layers[name] = layer
    for layer in layers.values():
        layer.use_pass_combined = True
        layer.use_pass_z = True
        layer.use_pass_vector = True
    return layers


def build(width, height, name, moves):
    """Scene `name` (one of SCENES), the camera moving as `moves` says (truck, pan, still)."""
    scene, fg, bg = setup(width, height)
    # The objects in the order the fan's scene always made them (the wall, the boxes, the
    # foreground, the camera), so its renders keep their bits.
    wall(bg)
    if name == "fan":
        fan_scene(fg, bg)
    else:
        gear(fg, name.removeprefix("gear-"))
    camera(scene, moves)
    return scene, view_layers(scene)


def main():
    args = arguments()
    width, height = (int(v) for v in args.size.split("x"))
    first, last = (int(v) for v in args.frames.split("-"))
    moves = args.camera or ("truck" if args.scene == "fan" else "still")
    scene, layers = build(width, height, args.scene, moves)
    scene.cycles.samples = args.samples
    scene.cycles.seed = args.seed
    scene.frame_start, scene.frame_end = first, last
    camera = scene.camera.data

    render = {"layers": ["FG", "BG"], "fg": ["FG"], "reference_fg": ["FG"]}
    render = render.get(args.kind, ["ViewLayer"])
    for name, layer in layers.items():
        layer.use = name in render
    others = layers["FG"].layer_collection.children["BG"]
    others.exclude = args.others == "exclude"
    others.holdout = args.others == "holdout"
    others.indirect_only = args.others == "indirect"
    motion = args.kind in ("reference", "reference_fg")
    scene.render.use_motion_blur = motion
    scene.render.motion_blur_shutter = SHUTTER
    # Cycles' Motion Blur > Position; where it lives moved between versions.
    for owner in (scene.render, scene.cycles):
        if hasattr(owner, "motion_blur_position"):
            owner.motion_blur_position = "CENTER"
    camera.dof.use_dof = args.kind == "reference_dof"
    if motion:
        # Cycles offers no Vector pass with motion blur on.
        for layer in layers.values():
            layer.use_pass_vector = False
    name = args.name or (f"fg_{args.others}" if args.kind == "fg" else args.kind)
    scene.render.filepath = f"{args.out}/{name}.####"
    bpy.ops.render.render(animation=True)


main()
