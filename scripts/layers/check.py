"""What Blender wrote, in numbers, and the error table (run in the venv: numpy, OpenEXR).

    python check.py facts OUT FRAME          # the layer outputs' facts, from OUT/*.FRAME.exr
    python check.py table OUT FRAMES...      # the table from OUT/score/*.json (run.sh)
"""

import json
import sys

import numpy as np
import OpenEXR


def load(path):
    """Every channel of every part by its full name (`FG.Combined.R`, `FG.Depth.Z`)."""
    out = {}
    for part in OpenEXR.File(path).parts:
        for name, channel in part.channels.items():
            pixels = channel.pixels
            if pixels.ndim == 3:  # the module groups R, G, B, A of a layer into one array
                for i, c in enumerate("RGBA"[: pixels.shape[2]]):
                    out[f"{name}.{c}"] = pixels[..., i]
            else:
                out[name] = pixels
    return out


def layer(channels, name):
    rgba = np.stack([channels[f"{name}.Combined.{c}"] for c in "RGBA"], -1)
    depth = channels[f"{name}.Depth.Z"]
    vector = np.stack([channels[f"{name}.Vector.{c}"] for c in "XYZW"], -1)
    return rgba, depth, vector


def rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def facts(out, frame):
    f = f"{int(frame):04d}"
    fg, fz, fv = layer(load(f"{out}/layers.{f}.exr"), "FG")
    bg, bz, bv = layer(load(f"{out}/layers.{f}.exr"), "BG")
    sc, sz, sv = layer(load(f"{out}/single.{f}.exr"), "ViewLayer")
    a = fg[..., 3]
    a1 = a[..., None]
    empty, full, edge = a == 0, a == 1, (a > 0) & (a < 1)
    samples = int(OpenEXR.File(f"{out}/layers.{f}.exr").parts[0].header["cycles.FG.samples"])
    q = a[edge] * samples
    print(f"frame {frame}, {a.shape[1]}x{a.shape[0]}")
    print(f"FG alpha: {empty.sum()} px 0, {full.sum()} px 1, {edge.sum()} px between; "
          f"alpha x {samples} (the samples) is a whole number at "
          f"{np.isclose(q, np.round(q), atol=1e-3).mean():.0%} of those")
    print(f"empty FG px: RGBA max {np.abs(fg[empty]).max():g}; Depth.Z values "
          f"{np.unique(fz[empty])}; Vector values {np.unique(fv[empty])}")
    print(f"opaque FG px: Depth.Z {fz[full].min():.4f}..{fz[full].max():.4f}")

    # Depth: an average over the samples (misses at 1e10 included) would put edge values
    # between the surface's depth and 1e10; one sample's depth is one or the other.
    hit = fz < 1e9
    between = edge & hit & (fz > fz[full].max() + 0.01)
    print(f"edge FG px: Depth.Z is the FG surface's at {hit[edge].sum()}, 1e10 at "
          f"{(~hit)[edge].sum()}, a value between at {between.sum()}")
    for lo, hi in ((0, 0.1), (0.1, 0.3), (0.3, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 1.0)):
        s = edge & (a > lo) & (a <= hi)
        print(f"  alpha in ({lo}, {hi}]: {s.sum():4d} px, "
              f"with the FG surface's depth {hit[s].mean():.1%}")
    one = np.isclose(sz, np.where(hit, fz, bz), rtol=1e-5)
    print(f"single layer at FG edge px: Depth.Z is the FG layer's where that is a hit, else the "
          f"BG layer's, at {one[edge].sum()} of {edge.sum()}")

    # Colour: premultiplied if FG over BG gives the one-layer render.
    over = fg + (1 - a1) * bg
    straight = fg[..., :3] * a1 + (1 - a1) * bg[..., :3]
    print(f"Combined: single vs FG over BG read premultiplied, RGB RMSE at FG edge px "
          f"{rms((over - sc)[edge][:, :3]):.4f} (whole frame {rms((over - sc)[..., :3]):.5f}); "
          f"read as straight alpha {rms((straight - sc[..., :3])[edge]):.4f}")
    print(f"  BG alpha min {bg[..., 3].min():g}, single alpha min {sc[..., 3].min():g}")

    # Vectors. In `layers` BG is a holdout in FG; fg_exclude and fg_indirect hold the others.
    print(f"Vector of layers' FG (BG holdout) at edge px: |X|,|Y| up to "
          f"{np.abs(fv[edge][:, :2]).max():.1f} px "
          f"(opaque px: {np.abs(fv[full][:, :2]).max():.1f})")
    for others in ("exclude", "indirect"):
        try:
            oc, oz, ov = layer(load(f"{out}/fg_{others}.{f}.exr"), "FG")
        except Exception:  # noqa: BLE001 - that variant was not rendered
            continue
        same = "==" if np.array_equal(oc, fg) else "!="
        same_z = "==" if np.array_equal(oz, fz) else "!="
        print(f"FG with BG {others}: Combined {same} and Depth {same_z} the holdout's; edge px "
              f"Vector vs alpha x the holdout's: RMSE {rms((ov - a1 * fv)[edge]):.2e} px, vs the "
              f"holdout's: {rms((ov - fv)[edge]):.3f} px; empty px {np.unique(ov[empty])}")
    mix = a1 * fv + (1 - a1) * bv
    print(f"single layer at FG edge px: Vector vs alpha x FG + (1 - alpha) x BG (holdout FG's): "
          f"RMSE {rms((sv - mix)[edge]):.3f} px; vs FG's alone {rms((sv - fv)[edge]):.3f} px")
    h, w = a.shape
    print(f"BG Depth.Z: {bz.min():.4f}..{bz.max():.4f}; the wall (flat, 1.795 m before the "
          f"camera) reads {bz[h // 2, w // 2]:.4f} at the centre and {bz[1, 1]:.4f} in a corner")
    try:
        ref = load(f"{out}/reference.{f}.exr")
        print(f"reference channels: {', '.join(sorted(ref))}")
    except Exception:  # noqa: BLE001 - not rendered yet
        pass


ALGORITHMS = ("reconstruct", "scatter", "stretch")
# (title, the noise file: two references of independent samples, rows: (label, score name
# with {alg} for each algorithm, or a name without it for one figure in every column)).
MOTION = [
    (
        "the whole frame against Cycles' motion blur (`reference`)",
        "noise",
        [
            ("single layer, sharp (no blur)", "none"),
            ("single layer", "single_{alg}"),
            ("FG over BG, BG holdout in FG", "merged_{alg}"),
            ("FG over BG, BG excluded from FG", "merged_exclude_{alg}"),
            ("`--layers FG,BG` (BG holdout in FG)", "stack_{alg}"),
            ("`--layers FG,BG`, FG with BG excluded (`--color` twice)", "stack_exclude_{alg}"),
        ],
    ),
    (
        "the FG layer alone (RGBA) against Cycles' FG layer with motion blur (`reference_fg`)",
        "fg_noise",
        [
            ("FG layer, sharp (no blur)", "fg_none"),
            ("FG layer, BG holdout in FG", "fg_{alg}"),
            ("FG layer, BG excluded from FG", "fg_exclude_{alg}"),
        ],
    ),
]
DOF = [
    ("sharp (no depth of field)", "dof_none"),
    ("single layer, gather", "dof_single_gather"),
    ("FG over BG, gather", "dof_merged_gather"),
    ("single layer, blend", "dof_single_blend"),
    ("FG over BG, blend", "dof_merged_blend"),
    ("`--layers FG,BG`, gather", "dof_stack_gather"),
    ("`--layers FG,BG`, blend", "dof_stack_blend"),
]


def region(path, index):
    """Frame `index`'s RMSE over the region the reference changes, from `shutter diff --json`."""
    return json.load(open(path))["frames"][index]["region"]["rmse"]


def table(out, frames):
    score = f"{out}/score"
    for i, frame in enumerate(frames):
        print(f"frame {frame}: RMSE over the region blur changes (the pixels where the reference "
              "differs from the sharp frame); in brackets with the reference's noise taken out, "
              "sqrt(RMSE² − noise²), noise = RMSE(reference, its seed-2 twin) / √2")
        for title, noise_name, rows in MOTION:
            noise = f"{score}/{noise_name}.json"
            n = region(noise, i) / np.sqrt(2) if _exists(noise) else 0.0
            print(f"\n{title}, reference noise {n:.5f}\n")
            print("| input | " + " | ".join(ALGORITHMS) + " |")
            print("|---|---|---|---|")
            for label, name in rows:
                cells = []
                for alg in ALGORITHMS:
                    path = f"{score}/{name.format(alg=alg)}.json"
                    if not _exists(path):
                        cells.append("—")
                        continue
                    r = region(path, i)
                    cells.append(f"{r:.5f} ({np.sqrt(max(0.0, r * r - n * n)):.5f})")
                print(f"| {label} | " + " | ".join(cells) + " |")
        rows = [(label, name) for label, name in DOF if _exists(f"{score}/{name}.json")]
        if rows:
            noise = f"{score}/dof_noise.json"
            n = region(noise, i) / np.sqrt(2) if _exists(noise) else 0.0
            print(f"\ndepth of field alone against Cycles' lens (`reference_dof`), "
                  f"reference noise {n:.5f}\n")
            print("| input | region RMSE |")
            print("|---|---|")
            for label, name in rows:
                r = region(f"{score}/{name}.json", i)
                print(f"| {label} | {r:.5f} ({np.sqrt(max(0.0, r * r - n * n)):.5f}) |")
        print()


def _exists(path):
    try:
        open(path).close()
        return True
    except OSError:
        return False


if __name__ == "__main__":
    if sys.argv[1] == "facts":
        facts(sys.argv[2], sys.argv[3])
    else:
        table(sys.argv[2], sys.argv[3:])
