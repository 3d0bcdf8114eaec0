#!/usr/bin/python3
"""Checks rviz screenshots of the hair_sim demo (rviz_screenshots.sh): hair pixels are present and move.

A pixel of rviz's 3D view (the central panel of config/hair_sim.rviz's 1280-wide layout) is a hair pixel
when it is brown and saturated: r > g > b and (r - b) / r > 0.45. The skin-coloured bodies, r:b = 217:143
((r - b) / r = 0.34, the same under shading), the grey background and the grid are not.
Asserted, for each shot: hair pixels > 3 % of the view. Between consecutive shots (1 s apart, the head
moving): the hair masks differ (XOR) in > 0.5 % of the view.
Usage: rviz_pixels.py SHOT.png SHOT.png [...]; prints the numbers; exit status 1 on failure.
       rviz_pixels.py --drawn SHOT.png: exit status 0 when the shot has hair pixels (> 3 % of the view), else 1
       (rviz_screenshots.sh waits for this before its shots: software rendering may take a while to draw).
"""
import sys

import numpy as np
from PIL import Image

VIEW = (slice(70, 690), slice(370, 975))  # rows, columns of the 3D view in a 1280 x 960 screen
MIN_HAIR = 0.03
MIN_MOVED = 0.005


def hair_mask(path):
    rgb = np.asarray(Image.open(path).convert('RGB'), dtype=np.float64)[VIEW]
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (r > g) & (g > b) & (r > 20) & ((r - b) > 0.45 * r)


def main(paths):
    masks = [hair_mask(p) for p in paths]
    ok = True
    for p, m in zip(paths, masks):
        fraction = m.mean()
        print('rviz_pixels: %s: hair pixels %.1f %% of the view' % (p, 100 * fraction))
        if fraction <= MIN_HAIR:
            print('rviz_pixels: FAIL: too few hair pixels (need > %.0f %%)' % (100 * MIN_HAIR))
            ok = False
    for a, b, pa, pb in zip(masks, masks[1:], paths, paths[1:]):
        moved = (a ^ b).mean()
        print('rviz_pixels: %s -> %s: hair moved in %.2f %% of the view' % (pa, pb, 100 * moved))
        if moved <= MIN_MOVED:
            print('rviz_pixels: FAIL: the hair did not move (need > %.1f %%)' % (100 * MIN_MOVED))
            ok = False
    return 0 if ok else 1


if __name__ == '__main__':
    if len(sys.argv) == 3 and sys.argv[1] == '--drawn':
        sys.exit(0 if hair_mask(sys.argv[2]).mean() > MIN_HAIR else 1)
    sys.exit(main(sys.argv[1:]))
