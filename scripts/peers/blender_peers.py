"""Inside Blender (bpy 5.x from PyPI, or `blender -b --python` for Debian's 3.4): runs the
compositor's Vector Blur and Defocus on the bench's scenes, as peers.py prepared them, and
writes one EXR per setting and OUT/peers/blender-X.Y/entries.json for peers.py merge.

    python blender_peers.py OUT SCENE... [--runs N]                 # bpy module
    blender -b --factory-startup --python blender_peers.py -- OUT SCENE... [--runs N]

Matched settings (README, "Peers"):
- Vector Blur: 32 samples; shutter = the bench's shutter fraction (0.5: the exposure spans
  t in [-0.25, +0.25] frames). 5.x takes it as the Shutter socket (frames the shutter is
  open); 3.4 as the node's Blur factor, which scales the same two half-vectors by up to
  factor / 2 each. No speed limits, straight (not curved) paths.
- Defocus: the scene's thin lens. Blender 5.x computes the CoC of the camera (focal length,
  sensor width with horizontal fit, focus distance) and the node's f-stop with the thin-lens
  formula we use, as a radius: ours / 2. Blender 3.4's formula differs (a 1000/sensor scale
  and a constant term, see lens_34), so its f-stop and focus distance are set to give the
  same radius at every depth. blur_max (a radius, px) is swept.

Times: compute_ms is the median over --runs of the render call with the inputs already
decoded (the compositor and Blender's render pipeline around it); end_to_end_ms the median
of reloading the inputs from disk, the render call and writing the EXR.
"""

import json
import os
import statistics
import sys
import time

import bpy

VERSION = bpy.app.version
NEW_API = VERSION >= (5, 0, 0)
NAME = f"blender {VERSION[0]}.{VERSION[1]}"
SAMPLES = 32
BLUR_MAX = [2, 4, 8, 16, 32]
# Blur_max of the Defocus before Vector Blur on a target with both: ours clamps the CoC
# diameter at 48 px (--max-coc), a radius of 24.
BLUR_MAX_BOTH = 24


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    runs = 5
    if "--runs" in argv:
        i = argv.index("--runs")
        runs = int(argv[i + 1])
        del argv[i : i + 2]
    return argv[0], argv[1:], runs


def lens_34(lens, width, height):
    """Blender 3.4's Defocus (ConvertDepthToRadiusOperation) computes
        r = 0.5 * |a * (s * (1/P' - 1/Z) - 1)|,  a = 0.5 * F / (aspect * S * N'),
        s = min(w, h) * 2F / S,  aspect = min(w, h) / max(w, h)
    with F and S in mm and Z, P' in scene units. For w >= h that is
        r = 0.5 * w * F^2 / (S^2 N') * |1/P' - S/(2hF) - 1/Z|.
    The thin lens (ours, in metres, as a radius) is
        r = 0.5 * (w / S_m) * F_m^2 * P / (N (P - F_m)) * |1/Z - 1/P|.
    They agree at every depth when 1/P' = 1/P + S/(2hF) and
        N' = 1000 N (P - F_m) / (S P).
    """
    f, s, n, p = lens["focal_mm"], lens["sensor_mm"], lens["f_number"], lens["focus"]
    short = min(width, height)
    if width < height:
        raise SystemExit("peers: the 3.4 lens mapping assumes a landscape frame")
    focus = 1.0 / (1.0 / p + s / (2.0 * short * f))
    f_stop = 1000.0 * n * (p - f / 1000.0) / (s * p)
    return focus, f_stop


def setup_scene(width, height, lens):
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    render = scene.render
    render.resolution_x, render.resolution_y = width, height
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.use_compositing = True
    render.use_sequencer = False
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    render.image_settings.color_mode = "RGBA"
    render.image_settings.exr_codec = "ZIP"
    if NEW_API:
        render.compositor_device = "CPU"
        render.compositor_precision = "FULL"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    camera = bpy.data.cameras.new("peer")
    obj = bpy.data.objects.new("peer", camera)
    scene.collection.objects.link(obj)
    scene.camera = obj
    if lens:
        camera.lens = lens["focal_mm"]
        camera.sensor_fit = "HORIZONTAL"
        camera.sensor_width = lens["sensor_mm"]
        camera.dof.use_dof = True
        camera.dof.focus_distance = lens["focus"]
    return scene, camera


def load(path, data):
    image = bpy.data.images.load(path, check_existing=False)
    # Colour: the scene-linear role (Linear Rec.709 in 5.x, "Linear" in 3.4), no transform.
    image.colorspace_settings.name = "Non-Color" if data else ("Linear Rec.709" if NEW_API else "Linear")
    image.alpha_mode = "CHANNEL_PACKED"
    return image


def new_tree(scene):
    if NEW_API:
        tree = bpy.data.node_groups.new("peer", "CompositorNodeTree")
        tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
        scene.compositing_node_group = tree
        output = tree.nodes.new("NodeGroupOutput")
        return tree, output.inputs[0]
    scene.use_nodes = True
    tree = scene.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("CompositorNodeComposite")
    output.use_alpha = True
    return tree, output.inputs["Image"]


def image_node(tree, image):
    node = tree.nodes.new("CompositorNodeImage")
    node.image = image
    return node.outputs["Image"]


def red(tree, socket):
    node = tree.nodes.new("CompositorNodeSeparateColor")
    tree.links.new(socket, node.inputs[0])
    return node.outputs[0]


def vector_blur(tree, image, depth, speed):
    node = tree.nodes.new("CompositorNodeVecBlur")
    tree.links.new(image, node.inputs["Image"])
    tree.links.new(speed, node.inputs["Speed"])
    if NEW_API:
        tree.links.new(depth, node.inputs["Depth"] if "Depth" in node.inputs else node.inputs["Z"])
        node.inputs["Samples"].default_value = SAMPLES
        node.inputs["Shutter"].default_value = SHUTTER
    else:
        tree.links.new(depth, node.inputs["Z"])
        node.samples = SAMPLES
        node.factor = SHUTTER
        node.speed_min = 0
        node.speed_max = 0
        node.use_curved = False
    return node.outputs["Image"]


def defocus(tree, image, depth, blur_max, f_stop):
    node = tree.nodes.new("CompositorNodeDefocus")
    tree.links.new(image, node.inputs["Image"])
    tree.links.new(depth, node.inputs["Z"])
    node.bokeh = "CIRCLE"
    node.angle = 0.0
    node.use_zbuffer = True
    node.f_stop = f_stop
    node.blur_max = blur_max
    if not NEW_API:
        node.use_preview = False
        node.use_gamma_correction = False
    return node.outputs["Image"]


def timed(images, output_path, runs):
    """Median render time with decoded inputs, and median reload + render + write time."""
    bpy.ops.render.render()  # warm-up: decodes the inputs, builds the compositor
    compute, end_to_end = [], []
    for _ in range(runs):
        t = time.perf_counter()
        bpy.ops.render.render()
        compute.append((time.perf_counter() - t) * 1e3)
    for _ in range(runs):
        t = time.perf_counter()
        for image in images:
            image.reload()
        bpy.ops.render.render()
        bpy.data.images["Render Result"].save_render(output_path)
        end_to_end.append((time.perf_counter() - t) * 1e3)
    return statistics.median(compute), statistics.median(end_to_end)


def main():
    global SHUTTER
    out, scenes, runs = arguments()
    label_dir = f"blender-{VERSION[0]}.{VERSION[1]}"
    peer_dir = os.path.join(out, "peers", label_dir)
    entries = []
    for scene_name in scenes:
        inputs = os.path.join(out, "peers", "inputs", scene_name)
        with open(os.path.join(inputs, "scene.json")) as f:
            description = json.load(f)
        width, height = description["width"], description["height"]
        SHUTTER = description["shutter"]
        lens = description.get("lens")
        scene, camera = setup_scene(width, height, lens)
        color = load(os.path.join(inputs, "color.exr"), data=False)
        depth_image = load(os.path.join(inputs, "depth.exr"), data=True)
        speed_image = load(os.path.join(inputs, "speed.exr"), data=True)
        images = [color, depth_image, speed_image]
        os.makedirs(os.path.join(peer_dir, scene_name), exist_ok=True)

        def run(label, file_stem, target, settings, build):
            tree, final = new_tree(scene)
            tree.links.new(build(tree), final)
            output = os.path.join(label_dir, scene_name, file_stem + ".exr")
            compute, end_to_end = timed(images, os.path.join(out, "peers", output), runs)
            print(f"peers: {scene_name}: {label}: {compute:.1f} ms", file=sys.stderr)
            entries.append(
                {
                    "label": label,
                    "peer": f"blender {bpy.app.version_string}",
                    "scene": scene_name,
                    "target": target,
                    "output": output,
                    "compute_ms": compute,
                    "end_to_end_ms": end_to_end,
                    "settings": settings,
                }
            )

        def passes(tree):
            return (
                image_node(tree, color),
                red(tree, image_node(tree, depth_image)),
                image_node(tree, speed_image),
            )

        motion = {"samples": SAMPLES, "shutter": SHUTTER}
        run(
            f"{NAME} vector blur S{SAMPLES}",
            f"vector_blur_S{SAMPLES}",
            scene_name,
            motion,
            lambda tree: vector_blur(tree, *passes(tree)),
        )
        if lens:
            if NEW_API:
                f_stop = lens["f_number"]
            else:
                focus, f_stop = lens_34(lens, width, height)
                camera.dof.focus_distance = focus
            for blur_max in BLUR_MAX:
                run(
                    f"{NAME} defocus bmax{blur_max}",
                    f"defocus_bmax{blur_max}",
                    f"{scene_name} dof",
                    {"blur_max": blur_max, "f_stop": f_stop,
                     "focus_distance": camera.dof.focus_distance},
                    lambda tree, b=blur_max: defocus(tree, *passes(tree)[:2], b, f_stop),
                )

            def both(tree):
                image, depth, speed = passes(tree)
                return vector_blur(tree, defocus(tree, image, depth, BLUR_MAX_BOTH, f_stop), depth, speed)

            run(
                f"{NAME} defocus bmax{BLUR_MAX_BOTH} + vector blur S{SAMPLES}",
                f"defocus_bmax{BLUR_MAX_BOTH}_vector_blur_S{SAMPLES}",
                f"{scene_name} dof+motion",
                {**motion, "blur_max": BLUR_MAX_BOTH, "f_stop": f_stop},
                both,
            )
        for image in images:
            bpy.data.images.remove(image)
    with open(os.path.join(peer_dir, "entries.json"), "w") as f:
        json.dump(entries, f, indent=2)


SHUTTER = 0.5
main()
