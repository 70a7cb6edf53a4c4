#!/usr/bin/env python3
"""Writes the corridor maps the wall compass was measured in on AMRISim
(ARIA .map, mm; robot home at the origin) into the folder given:

    python3 scripts/amrisim/maps.py OUT_DIR
"""
import math
import os
import sys

OUT = sys.argv[1]
def write(name, lines, home=(0, 0, 0)):
    xs = [v for l in lines for v in (l[0], l[2])]; ys = [v for l in lines for v in (l[1], l[3])]
    with open(os.path.join(OUT, f"{name}.map"), "w") as f:
        f.write("2D-Map\n")
        f.write(f"LineMinPos: {int(min(xs))} {int(min(ys))}\nLineMaxPos: {int(max(xs))+1} {int(max(ys))+1}\nNumLines: {len(lines)}\n")
        f.write(f'Cairn: RobotHome {home[0]} {home[1]} {home[2]} "" ICON "Home"\nLINES\n')
        for l in lines:
            f.write(" ".join(str(int(round(v))) for v in l) + "\n")
        f.write("DATA\n")
H = 1250  # half width: 2.5 m corridor
X0, X1 = -2000, 34000
# 1. square straight corridor
write("straight", [(X0, H, X1, H), (X0, -H, X1, -H), (X0, -H, X0, H), (X1, -H, X1, H)])
# 2. the same corridor with both long walls rotated 3 degrees about the start
def rot(p, a):
    c, s = math.cos(a), math.sin(a); return (p[0]*c - p[1]*s, p[0]*s + p[1]*c)
a = math.radians(3)
pts = [rot(p, a) for p in [(X0, H), (X1, H), (X0, -H), (X1, -H)]]
write("rot3", [(*pts[0], *pts[1]), (*pts[2], *pts[3]), (*pts[2], *pts[0]), (*pts[3], *pts[1])])
# 3. straight for 10 m, then bending 5 degrees over 20 m (5 segments of 4 m, +1 degree each)
def bent(h):
    pts = [(X0, h), (10000, h)]; x, y, th = 10000.0, float(h), 0.0
    for k in range(1, 6):
        th = math.radians(k); x += 4000*math.cos(th); y += 4000*math.sin(th); pts.append((x, y))
    x += 2000*math.cos(th); y += 2000*math.sin(th); pts.append((x, y))
    return pts
# centreline offset: walls offset perpendicular approx (small angles): shift each wall by +-H along the normal
def offset(center, d):
    out = []
    for i, p in enumerate(center):
        j = min(i, len(center)-2); q0, q1 = center[j], center[j+1]
        th = math.atan2(q1[1]-q0[1], q1[0]-q0[0]); out.append((p[0]-d*math.sin(th), p[1]+d*math.cos(th)))
    return out
c = bent(0); L, R = offset(c, H), offset(c, -H)
lines = [(*L[i], *L[i+1]) for i in range(len(L)-1)] + [(*R[i], *R[i+1]) for i in range(len(R)-1)]
lines += [(*R[0], *L[0]), (*R[-1], *L[-1])]
write("bend5", lines)
with open(os.path.join(OUT, "bend5.centre.txt"), "w") as f:
    f.write("\n".join(f"{p[0]:.0f} {p[1]:.0f}" for p in c) + "\n")
# 4. L route: 14 m along +x (2.5 m wide), then left along +y for 22 m (2.5 m wide)
W = H
lines = [
  (X0, -W, 14000 + W, -W),        # right wall of leg 1, continues to the outer corner
  (14000 + W, -W, 14000 + W, 24000),  # outer wall of leg 2
  (X0, W, 14000 - W, W),          # left wall of leg 1 up to the inner corner
  (14000 - W, W, 14000 - W, 24000),   # inner wall of leg 2
  (X0, -W, X0, W), (14000 - W, 24000, 14000 + W, 24000)]
write("L", lines)
