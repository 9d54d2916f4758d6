"""Distance from a point to a closed polyline (a piece's sew line read back from the DXF): the seam
allowance checks of tests/export/test_pattern_cli.sh.
SPDX-License-Identifier: GPL-3.0-or-later
"""
import math


def distance_to_loop(p, loop):
    best = math.inf
    for i in range(len(loop)):
        a, b = loop[i], loop[(i + 1) % len(loop)]
        dx, dy = b[0] - a[0], b[1] - a[1]
        t = max(0, min(1, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy or 1)))
        best = min(best, math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy))
    return best
