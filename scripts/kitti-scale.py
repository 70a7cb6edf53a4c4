#!/usr/bin/env python3
"""Where a KITTI sequence's step-length over-estimate comes from, measured
with OpenCV alone (none of our pipeline), against the ground-truth poses.

    python3 scripts/kitti-scale.py DIR

DIR is a KITTI odometry sequence with poses.txt. For each frame step, OpenCV
finds ORB corners in both left images, reads each corner's depth from
StereoSGBM's disparity in the first pair (calib.txt's focal length and
baseline), and solves the second camera's pose with solvePnPRansac (3D in the
first frame, 2D in the second). The step length over the true one is the
step scale; its median is printed for all landmarks and for landmarks in
bands of disparity.

A scale error that grows as the disparity shrinks, as δ / d, is what a
disparity offset δ left by the calibration does: far landmarks' depths are
inflated by more than near ones'. The last column gives the δ each band
implies. The script installs opencv-python-headless and numpy into
.venv-opencv on first use (scripts/script_env.py).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import script_env  # noqa: E402  (scripts/script_env.py)

BANDS = [(1, 1e9), (4, 10), (10, 20), (20, 40), (40, 1e9)]


def main():
    script_env.ensure(".venv-opencv", ["opencv-python-headless", "numpy"], ["cv2", "numpy"])
    import cv2
    import numpy as np

    if len(sys.argv) != 2:
        sys.exit(__doc__)
    directory = sys.argv[1]
    rows = {}
    for line in open(os.path.join(directory, "calib.txt")):
        name, _, numbers = line.partition(":")
        rows[name.strip()] = [float(v) for v in numbers.split()]
    p0, p1 = rows["P0"], rows["P1"]
    f, cx, cy, baseline = p0[0], p0[2], p0[6], -p1[3] / p1[0]
    camera = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1.0]])
    poses = np.loadtxt(os.path.join(directory, "poses.txt")).reshape(-1, 3, 4)
    image = lambda side, i: cv2.imread(os.path.join(directory, f"image_{side}", f"{i:06d}.png"), cv2.IMREAD_GRAYSCALE)
    sgbm = cv2.StereoSGBM_create(
        minDisparity=0, numDisparities=128, blockSize=5, P1=8 * 25, P2=32 * 25,
        uniquenessRatio=10, speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_HH,
    )
    orb = cv2.ORB_create(3000)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)
    cv2.setRNGSeed(0)
    steps = []
    for i in range(len(poses) - 1):
        left, right, after = image(0, i), image(1, i), image(0, i + 1)
        disparity = sgbm.compute(left, right).astype(np.float32) / 16
        k0, d0 = orb.detectAndCompute(left, None)
        k1, d1 = orb.detectAndCompute(after, None)
        points, pixels, disparities = [], [], []
        for m in matcher.match(d0, d1):
            u, v = k0[m.queryIdx].pt
            d = disparity[int(round(v)), int(round(u))]
            if d <= 0:
                continue
            z = f * baseline / d
            points.append([(u - cx) * z / f, (v - cy) * z / f, z])
            pixels.append(k1[m.trainIdx].pt)
            disparities.append(d)
        true_step = (np.linalg.inv(np.vstack([poses[i], [0, 0, 0, 1]])) @ np.vstack([poses[i + 1], [0, 0, 0, 1]]))[:3, 3]
        steps.append((np.array(points), np.array(pixels), np.array(disparities), np.linalg.norm(true_step)))
    print("| disparity band px | median disparity px | steps | step scale (median) | implied offset px |")
    print("| --- | --- | --- | --- | --- |")
    for low, high in BANDS:
        scales, medians = [], []
        for points, pixels, disparities, true_length in steps:
            keep = (disparities >= low) & (disparities < high)
            if keep.sum() < 12:
                continue
            ok, rvec, tvec, inliers = cv2.solvePnPRansac(
                points[keep], pixels[keep], camera, None, reprojectionError=1.0, iterationsCount=500
            )
            if not ok or inliers is None or len(inliers) < 6:
                continue
            chosen = inliers[:, 0]
            ok, rvec, tvec = cv2.solvePnP(points[keep][chosen], pixels[keep][chosen], camera, None, rvec, tvec, True)
            rotation, _ = cv2.Rodrigues(rvec)
            scales.append(np.linalg.norm(-rotation.T @ tvec.ravel()) / true_length)
            medians.append(np.median(disparities[keep]))
        if not scales:
            continue
        scale, d = float(np.median(scales)), float(np.median(medians))
        band = f"{low:g}+" if high > 1e8 else f"{low:g}-{high:g}"
        print(f"| {band} | {d:.1f} | {len(scales)} | {scale:.4f} | {(scale - 1) * d:+.3f} |")


if __name__ == "__main__":
    main()
