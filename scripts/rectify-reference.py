#!/usr/bin/env python3
"""OpenCV's rectification of one calibrated stereo pair, as reference values.

    python3 scripts/rectify-reference.py

Runs OpenCV's stereoRectify (CALIB_ZERO_DISPARITY, alpha -1) and
initUndistortRectifyMap on a fixed, realistic calibration (a 1280 x 720
pair, 12 cm baseline, strong barrel distortion, the right camera turned
1.2 degrees and shifted 3 mm), writes the pair as ROS camera_info files
into perception/tests/data/ (and the unrectified calibration, K1, D1, K2,
D2, R, T, as OpenCV's FileStorage writes it, into stereo.yaml), and prints where the maps sample the raw
images for a grid of rectified pixels: the numbers
perception/tests/rectify.rs checks our tables against. Uses the same
virtual environment as opencv-compare.py.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
opencv_compare = __import__("opencv-compare")


def camera_info(name, size, k, d, r, p):
    def matrix(rows, cols, values):
        data = ", ".join(f"{v:.12g}" for v in values)
        return f"  rows: {rows}\n  cols: {cols}\n  data: [{data}]\n"
    return (f"image_width: {size[0]}\nimage_height: {size[1]}\ncamera_name: {name}\n"
            f"camera_matrix:\n{matrix(3, 3, k.flatten())}"
            f"distortion_model: plumb_bob\ndistortion_coefficients:\n{matrix(1, 5, d.flatten())}"
            f"rectification_matrix:\n{matrix(3, 3, r.flatten())}"
            f"projection_matrix:\n{matrix(3, 4, p.flatten())}")


def main():
    opencv_compare.ensure_opencv()
    import cv2
    import numpy as np

    size = (1280, 720)
    k1 = np.array([[910.0, 0, 652.3], [0, 908.5, 361.8], [0, 0, 1]])
    k2 = np.array([[905.2, 0, 631.7], [0, 904.1, 355.2], [0, 0, 1]])
    d1 = np.array([-0.31, 0.11, 0.0007, -0.0004, -0.018])
    d2 = np.array([-0.29, 0.095, -0.0005, 0.0006, -0.012])
    rotation, _ = cv2.Rodrigues(np.array([0.004, np.radians(1.2), -0.003]))
    translation = np.array([[-0.12], [0.003], [0.001]])
    r1, r2, p1, p2, _, _, _ = cv2.stereoRectify(k1, d1, k2, d2, size, rotation, translation,
                                                flags=cv2.CALIB_ZERO_DISPARITY, alpha=-1)
    out = os.path.join(opencv_compare.ROOT, "perception", "tests", "data")
    os.makedirs(out, exist_ok=True)
    # The unrectified calibration, as OpenCV's FileStorage writes what
    # stereoCalibrate returns.
    storage = cv2.FileStorage(os.path.join(out, "stereo.yaml"), cv2.FILE_STORAGE_WRITE)
    storage.write("image_width", size[0])
    storage.write("image_height", size[1])
    for name, value in [("K1", k1), ("D1", d1.reshape(1, 5)), ("K2", k2), ("D2", d2.reshape(1, 5)),
                        ("R", rotation), ("T", translation)]:
        storage.write(name, value)
    storage.release()
    for name, k, d, r, p in [("left", k1, d1, r1, p1), ("right", k2, d2, r2, p2)]:
        with open(os.path.join(out, f"{name}.yaml"), "w") as f:
            f.write(camera_info(name, size, k, d, r, p))
        mx, my = cv2.initUndistortRectifyMap(k, d, r, p, size, cv2.CV_32FC1)
        for v in range(0, size[1], 90):
            for u in range(0, size[0], 160):
                print(f"({name!r}, {u}, {v}, {mx[v, u]:.4f}, {my[v, u]:.4f}),")


if __name__ == "__main__":
    main()
