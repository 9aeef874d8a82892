"""Outside Blender (the venv's Python, with numpy and OpenEXR): prepares the bench's scene
files as Blender reads them, and merges the Blender runs' lists into peers.json.

    python peers.py prepare OUT SCENE...   # OUT/scenes/SCENE/*.0001.exr -> OUT/peers/inputs/SCENE/
    python peers.py merge OUT              # OUT/peers/blender-*/entries.json -> OUT/peers/peers.json

Blender's compositor takes a 4-channel Speed (its Vector pass): X,Y = p(-1) - p(0) and
Z,W = p(0) - p(+1), in pixels, y up. The bench writes shutter's canonical passes: velocity
v = p(0) - p(-1) and the absolute next position p(+1), y down, with p(0) the pixel centre.
So, with c the pixel centre (i + 0.5, j + 0.5) and y negated for y up:

    X = -v.x        Y = +v.y        Z = c.x - next.x        W = next.y - c.y

Rows are not flipped here: Blender reads an EXR's first row as the top of the image, as we
do; only vectors change sign. Depth goes into R, G and B (Blender takes R through a Separate
Color node), colour as it is.
"""

import glob
import json
import os
import sys

import numpy as np
import OpenEXR


def read_channels(path):
    with OpenEXR.File(path, separate_channels=True) as f:
        return {name: np.asarray(ch.pixels, dtype=np.float32) for name, ch in f.channels().items()}


def write_rgba(path, r, g, b, a):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {name: np.ascontiguousarray(p, dtype=np.float32) for name, p in zip("RGBA", (r, g, b, a))}
    with OpenEXR.File(header, channels) as f:
        f.write(path)


def prepare(out, scenes):
    for scene in scenes:
        src = os.path.join(out, "scenes", scene)
        dst = os.path.join(out, "peers", "inputs", scene)
        os.makedirs(dst, exist_ok=True)
        color = read_channels(os.path.join(src, "color.0001.exr"))
        depth = read_channels(os.path.join(src, "depth.0001.exr"))["Z"]
        velocity = read_channels(os.path.join(src, "velocity.0001.exr"))
        nxt = read_channels(os.path.join(src, "next.0001.exr"))
        h, w = depth.shape
        cx = np.arange(w, dtype=np.float64)[None, :] + 0.5
        cy = np.arange(h, dtype=np.float64)[:, None] + 0.5
        speed = (
            -velocity["X"].astype(np.float64),
            velocity["Y"].astype(np.float64),
            cx - nxt["X"].astype(np.float64),
            nxt["Y"].astype(np.float64) - cy,
        )
        alpha = color.get("A", np.ones_like(depth))
        write_rgba(os.path.join(dst, "color.exr"), color["R"], color["G"], color["B"], alpha)
        one = np.ones_like(depth)
        write_rgba(os.path.join(dst, "depth.exr"), depth, depth, depth, one)
        write_rgba(os.path.join(dst, "speed.exr"), *speed)
        with open(os.path.join(src, "scene.json")) as f:
            description = json.load(f)
        with open(os.path.join(dst, "scene.json"), "w") as f:
            json.dump(description, f, indent=2)
        print(f"peers: prepared {scene} ({w}x{h})", file=sys.stderr)


def merge(out):
    peers_dir = os.path.join(out, "peers")
    entries = []
    for path in sorted(glob.glob(os.path.join(peers_dir, "blender-*", "entries.json"))):
        with open(path) as f:
            entries.extend(json.load(f))
    with open(os.path.join(peers_dir, "peers.json"), "w") as f:
        json.dump({"peers": entries}, f, indent=2)
    print(f"peers: {len(entries)} outputs in {peers_dir}/peers.json", file=sys.stderr)


if __name__ == "__main__":
    command, out, *rest = sys.argv[1:]
    if command == "prepare":
        prepare(out, rest)
    elif command == "merge":
        merge(out)
    else:
        sys.exit(f"unknown command {command}")
