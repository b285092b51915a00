#!/usr/bin/env python3
"""Mean LDR-FLIP and HDR-FLIP of NVIDIA's own implementation on two synthetic image pairs.

tests/metrics.rs builds the same images (the formulas below, in f64, stored as f32) and checks
hybrid-rt's FLIP against the numbers this script prints. NVIDIA's reference images are not
reachable from the build machines, but their implementation is on PyPI:

    python3 -m venv /tmp/flip && /tmp/flip/bin/pip install flip-evaluator==1.7
    /tmp/flip/bin/python tools/flip_reference_values.py
"""
import math

import flip_evaluator as flip
import numpy as np

W, H = 160, 120


def ldr_pair():
    ref = np.zeros((H, W, 3))
    test = np.zeros((H, W, 3))
    for y in range(H):
        for x in range(W):
            for c in range(3):
                r = 0.5 + 0.4 * math.sin(0.21 * x + 1.3 * c) * math.cos(0.17 * y)
                e = 0.08 * math.sin(0.9 * x + 0.7 * y + c)
                if 60 <= x < 72 and 40 <= y < 52:
                    e += 0.35
                ref[y, x, c] = r
                test[y, x, c] = min(max(r + e, 0.0), 1.0)
    return ref.astype(np.float32), test.astype(np.float32)


def hdr_pair():
    ref = np.zeros((H, W, 3))
    test = np.zeros((H, W, 3))
    for y in range(H):
        for x in range(W):
            for c in range(3):
                r = 2.0 ** (5.0 * math.sin(0.05 * x + 0.4 * c) * math.cos(0.043 * y))
                f = 1.0 + 0.2 * math.sin(0.8 * x + 1.1 * y + c)
                if 100 <= x < 110 and 20 <= y < 30:
                    f *= 8.0
                ref[y, x, c] = r
                test[y, x, c] = r * f
    return ref.astype(np.float32), test.astype(np.float32)


if __name__ == "__main__":
    ref, test = ldr_pair()
    _, ldr, _ = flip.evaluate(ref, test, "LDR", inputsRGB=True, applyMagma=False)
    ref, test = hdr_pair()
    _, hdr, params = flip.evaluate(ref, test, "HDR", applyMagma=False)
    print(f"LDR-FLIP mean {ldr:.6f}")
    print(f"HDR-FLIP mean {hdr:.6f} (exposures {params['startExposure']:.4f} to "
          f"{params['stopExposure']:.4f} in {params['numExposures']} steps)")
