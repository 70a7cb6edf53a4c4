#!/usr/bin/env python3
"""Times OpenCV on the same stereo pairs as `ubf pipeline`, and prints both.

    python3 scripts/opencv-compare.py DIR [--ubf PATH]

DIR is a directory written by `ubf frames` (frames.csv, camera.ron, left/,
right/), or a KITTI odometry sequence (calib.txt, times.txt, image_0/,
image_1/). The script creates a virtual environment in .venv-opencv beside
the repository's scripts/ and installs opencv-python-headless and numpy
into it on first use, then re-runs itself there.

Per pair, OpenCV does what our pipeline does, on one thread:
  ORB (FAST corners + rotated BRIEF) on both images, up to 1000 each;
  brute-force Hamming matching left to right, keeping matches on the same
  row (±1 px), with positive disparity, under the distance threshold and
  passing the ratio test; triangulation; matching the left descriptors to
  the previous pair's; and a rigid planar estimate of the motion with
  RANSAC (estimateAffinePartial2D on the floor-plane points).
The median time per pair is compared with `ubf pipeline DIR --json`. On a
KITTI sequence with poses.txt, the motions are chained frame to frame and
both pipelines' end-point drift (end-point error over the path length, in
the ground plane) and failed steps are printed too.
"""
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import script_env  # noqa: E402  (scripts/script_env.py)

ROOT = script_env.ROOT


def ensure_opencv():
    script_env.ensure(".venv-opencv", ["opencv-python-headless", "numpy"], ["cv2", "numpy"])


def kitti(directory):
    """Focal length, principal point, baseline and the pairs of a KITTI sequence."""
    rows = {}
    for line in open(os.path.join(directory, "calib.txt")):
        name, _, numbers = line.partition(":")
        rows[name.strip()] = [float(v) for v in numbers.split()]
    p0, p1 = rows["P0"], rows["P1"]
    count = sum(1 for line in open(os.path.join(directory, "times.txt")) if line.strip())
    pairs = [(f"image_0/{i:06d}.png", f"image_1/{i:06d}.png") for i in range(count)]
    # OpenCV's pixel centres are at integers, as KITTI's principal point is.
    return (p0[0], p0[2], p0[6], -p1[3] / p1[0]), pairs


def camera(directory):
    """Focal length, principal point and baseline from camera.ron (or the defaults)."""
    values = {"width_px": 640.0, "height_px": 480.0, "focal_px": 554.2562584220408, "baseline_m": 0.6}
    path = os.path.join(directory, "camera.ron")
    if os.path.exists(path):
        for line in open(path):
            key, _, value = line.strip().rstrip(",").partition(":")
            if key.strip() in values:
                values[key.strip()] = float(value)
    return values["focal_px"], values["width_px"] / 2, values["height_px"] / 2, values["baseline_m"]


def main():
    ensure_opencv()
    import cv2
    import numpy as np

    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    directory = args[0]
    ubf = os.path.join(ROOT, "target", "release", "ubf")
    if "--ubf" in args:
        ubf = args[args.index("--ubf") + 1]
    cv2.setNumThreads(1)
    if os.path.exists(os.path.join(directory, "calib.txt")):
        (f, cx, cy, baseline), pairs = kitti(directory)
    else:
        f, cx, cy, baseline = camera(directory)
        lines = open(os.path.join(directory, "frames.csv")).read().split("\n")[1:]
        pairs = [l.split(",")[1:] for l in lines if l.strip()]
    images = [(cv2.imread(os.path.join(directory, l), cv2.IMREAD_GRAYSCALE),
               cv2.imread(os.path.join(directory, r), cv2.IMREAD_GRAYSCALE)) for l, r in pairs]
    orb = cv2.ORB_create(nfeatures=1000, fastThreshold=20)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    times, counts, previous = [], [], None
    # The left camera's pose in the first frame (4 × 4), its path in the
    # floor plane (x right, z ahead), and the steps with no estimate.
    pose, path, failed = np.eye(4), [(0.0, 0.0)], 0
    intrinsics = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1]], dtype=np.float64)
    for left, right in images:
        start = time.perf_counter()
        kl, dl = orb.detectAndCompute(left, None)
        kr, dr = orb.detectAndCompute(right, None)
        points, descriptors = [], []
        if dl is not None and dr is not None and len(dr) >= 2:
            # Only right features on the same row (±1 px) with positive
            # disparity are candidates: a mask, so the search stays in C++.
            pl = np.float32([k.pt for k in kl])
            pr = np.float32([k.pt for k in kr])
            mask = ((np.abs(pl[:, None, 1] - pr[None, :, 1]) <= 1.0)
                    & (pl[:, None, 0] - pr[None, :, 0] >= 1.0)).astype(np.uint8)
            for pair in matcher.knnMatch(dl, dr, k=2, mask=mask):
                if not pair or pair[0].distance > 64:
                    continue
                if len(pair) == 2 and pair[0].distance >= 0.8 * pair[1].distance:
                    continue
                m = pair[0]
                (ul, v), (ur, _) = kl[m.queryIdx].pt, kr[m.trainIdx].pt
                depth = f * baseline / (ul - ur)
                points.append(((ul - cx) * depth / f, (v - cy) * depth / f, depth))
                descriptors.append(dl[m.queryIdx])
        points = np.array(points, dtype=np.float64).reshape(-1, 3)
        descriptors = np.array(descriptors, dtype=np.uint8)
        moved = None
        if previous is not None and len(previous[0]) >= 6 and dl is not None and len(dl) >= 2:
            good = [p[0] for p in matcher.knnMatch(previous[1], dl, k=2)
                    if len(p) == 2 and p[0].distance <= 64 and p[0].distance < 0.8 * p[1].distance]
            if len(good) >= 6:
                objects = np.float64([previous[0][m.queryIdx] for m in good])
                pixels = np.float64([kl[m.trainIdx].pt for m in good])
                ok, rvec, tvec, inliers = cv2.solvePnPRansac(
                    objects, pixels, intrinsics, None, iterationsCount=100, reprojectionError=1.0)
                if ok and inliers is not None and len(inliers) >= 6:
                    # The previous frame's points in this camera's frame:
                    # the camera moved by the inverse.
                    step = np.eye(4)
                    step[:3, :3], step[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
                    moved = step
        if previous is not None:
            if moved is None:
                failed += 1
            else:
                pose = pose @ np.linalg.inv(moved)
            path.append((pose[0, 3], pose[2, 3]))
        previous = (points, descriptors)
        times.append((time.perf_counter() - start) * 1e3)
        counts.append(len(points))
    times.sort()
    theirs = times[len(times) // 2]
    ours = json.loads(subprocess.check_output([ubf, "pipeline", directory, "--json"]))
    drift = None
    poses = os.path.join(directory, "poses.txt")
    if os.path.exists(poses):
        # KITTI's poses: the left camera's 3 × 4 matrix; x right, z ahead.
        truth = [[float(v) for v in line.split()] for line in open(poses) if line.strip()]
        along = sum(np.hypot(b[3] - a[3], b[11] - a[11]) for a, b in zip(truth, truth[1:]))
        end = truth[len(path) - 1]
        drift = np.hypot(path[-1][0] - end[3], path[-1][1] - end[11]) / along * 100
    print(f"{len(images)} stereo pairs from {directory}, one thread each")
    print(f"| pipeline | median ms per pair | pairs/s | landmarks per pair | drift % | failed steps |")
    print(f"| --- | --- | --- | --- | --- | --- |")
    ours_drift = f"{ours['endpoint_drift_pct']:.2f}" if "endpoint_drift_pct" in ours else "—"
    print(f"| ubf (FAST-9, 256-bit BRIEF, row matching, rigid RANSAC) | {ours['total_ms_median']:.2f} | "
          f"{ours['frames_per_s']:.0f} | {ours['landmarks_mean']:.0f} | {ours_drift} | {ours['failures']} |")
    theirs_drift = "—" if drift is None else f"{drift:.2f}"
    print(f"| OpenCV {cv2.__version__} (ORB, BFMatcher, solvePnPRansac) | {theirs:.2f} | "
          f"{1e3 / theirs:.0f} | {sum(counts) / len(counts):.0f} | {theirs_drift} | {failed} |")
    print(f"ubf's time is {ours['total_ms_median'] / theirs:.2f} of OpenCV's")


if __name__ == "__main__":
    main()
