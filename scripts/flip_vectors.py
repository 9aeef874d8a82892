#!/usr/bin/env python3
"""Expected mean LDR-FLIP errors for the image pairs in fixtures/flip/, computed with NVIDIA's
own implementation (the flip-evaluator package on PyPI), so that shutter's FLIP is checked
against it (tests/metrics.rs).

    pip install flip-evaluator==1.7 numpy
    cargo run --example make_fixtures      # writes fixtures/flip/*_{ref,test}.png
    python3 scripts/flip_vectors.py        # writes fixtures/flip/expected.json
"""
import json
import os
import sys

import flip_evaluator as flip

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures", "flip")
pairs = sorted(n[: -len("_ref.png")] for n in os.listdir(here) if n.endswith("_ref.png"))
expected = {}
for name in pairs:
    ref = os.path.join(here, f"{name}_ref.png")
    test = os.path.join(here, f"{name}_test.png")
    _, mean, params = flip.evaluate(ref, test, "LDR", applyMagma=False)
    expected[name] = {"mean_flip": float(mean), "ppd": float(params.get("ppd", 67.0))}
    print(f"{name}: {mean:.6f}", file=sys.stderr)
with open(os.path.join(here, "expected.json"), "w") as f:
    json.dump({"tool": "flip-evaluator 1.7 (LDR, 67 ppd)", "pairs": expected}, f, indent=2)
    f.write("\n")
