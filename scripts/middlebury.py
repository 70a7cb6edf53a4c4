#!/usr/bin/env python3
"""Disparity accuracy against ground truth: Middlebury 2014 Motorcycle.

    python3 scripts/middlebury.py [--ubf PATH]

scikit-image ships the Motorcycle pair at quarter size (741 x 500) with its
ground-truth disparity (skimage.data.stereo_motorcycle, Scharstein et al.,
GCPR 2014). The script installs scikit-image into .venv-skimage on first
use, writes the pair as a recording (frames.csv, grey PNGs, camera.ron
with the quarter-size calibration: f 994.98 px, principal point
(311.19, 254.88), baseline 0.193 m, disparity offset 31.09 px), runs
`ubf pipeline --landmarks` on it, and compares each landmark's disparity
with the ground truth at its pixel (where the ground truth is known). It
does the same with the right image at 0.6 of its exposure. Prints the
median and 90th percentile of the absolute error, px.
"""
import csv
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import script_env  # noqa: E402  (scripts/script_env.py)

ROOT = script_env.ROOT

# Middlebury 2014 Motorcycle (perfect rectification), calib.txt, divided by 4.
CAMERA = """(
    width_px: 741,
    height_px: 500,
    focal_px: 994.97775,
    baseline_m: 0.193001,
    principal_point: (x: 311.193, y: 254.87675),
    disparity_offset_px: 31.08575,
)
"""


def ensure_skimage():
    script_env.ensure(".venv-skimage", ["scikit-image"], ["skimage"])


def main():
    ensure_skimage()
    import numpy as np
    from skimage import data, io
    from skimage.color import rgb2gray

    args = sys.argv[1:]
    ubf = args[args.index("--ubf") + 1] if "--ubf" in args else os.path.join(ROOT, "target", "release", "ubf")
    left, right, truth = data.stereo_motorcycle()
    grey = lambda image: (rgb2gray(image) * 255).round().astype(np.uint8)
    print("| right image exposure | landmarks | median error px | 90th percentile px |")
    print("| --- | --- | --- | --- |")
    for gain in [1.0, 0.6]:
        with tempfile.TemporaryDirectory() as directory:
            io.imsave(os.path.join(directory, "left.png"), grey(left), check_contrast=False)
            dimmer = (grey(right).astype(np.float64) * gain).round().astype(np.uint8)
            io.imsave(os.path.join(directory, "right.png"), dimmer, check_contrast=False)
            with open(os.path.join(directory, "frames.csv"), "w") as f:
                f.write("time_s,left,right\n0.0,left.png,right.png\n")
            with open(os.path.join(directory, "camera.ron"), "w") as f:
                f.write(CAMERA)
            landmarks = os.path.join(directory, "landmarks.csv")
            subprocess.check_call([ubf, "pipeline", directory, "--landmarks", landmarks], stdout=subprocess.DEVNULL)
            errors = []
            for row in csv.DictReader(open(landmarks)):
                u, v = float(row["u_left_px"]), float(row["v_px"])
                expected = truth[int(round(v)), int(round(u))]
                if np.isfinite(expected):
                    errors.append(abs(float(row["disparity_px"]) - expected))
            errors = np.array(errors)
            print(f"| {gain:.1f} | {len(errors)} | {np.median(errors):.3f} | {np.percentile(errors, 90):.3f} |")


if __name__ == "__main__":
    main()
