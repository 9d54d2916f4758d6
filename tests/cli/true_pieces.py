"""Per-piece shape difference between a garment's true pattern (its own vt) and panelize's
(garment.obj written by `panelize run/flatten --panels uv`): the best rigid motion (a mirrored piece
may be flipped) of each output piece onto the true one, scaled to millimetres by the median ratio of
output to true edge lengths; the error is the RMS corner distance over the square root of the true
piece's area, in percent, and its area-weighted mean over the pieces.

usage: true_pieces.py TRUE.obj OUTPUT.obj MAX_PERCENT
prints one line per piece and the mean; exits 1 when the mean exceeds MAX_PERCENT.
SPDX-License-Identifier: GPL-3.0-or-later
"""
import math
import sys


def read(path):
    vt, faces, groups, group = [], [], [], None
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == 'vt':
            vt.append((float(t[1]), float(t[2])))
        elif t[0] == 'g':
            group = t[1]
        elif t[0] == 'f':
            faces.append([int(c.split('/')[1]) - 1 for c in t[1:4]])
            groups.append(group)
    return vt, faces, groups


def rigid_rms(a, b):
    """RMS distance of b to a after the best rotation and translation, b mirrored or not."""
    n = len(a)
    ca = (sum(p[0] for p in a) / n, sum(p[1] for p in a) / n)
    best = None
    for mirror in (1, -1):
        bm = [(mirror * x, y) for x, y in b]
        cb = (sum(p[0] for p in bm) / n, sum(p[1] for p in bm) / n)
        dot = cross = 0.0
        for (ax, ay), (bx, by) in zip(a, bm):
            ax, ay, bx, by = ax - ca[0], ay - ca[1], bx - cb[0], by - cb[1]
            dot += ax * bx + ay * by
            cross += ay * bx - ax * by
        angle = math.atan2(cross, dot)
        c, s = math.cos(angle), math.sin(angle)
        error = 0.0
        for (ax, ay), (bx, by) in zip(a, bm):
            bx, by = bx - cb[0], by - cb[1]
            error += (c * bx - s * by + ca[0] - ax) ** 2 + (s * bx + c * by + ca[1] - ay) ** 2
        error = math.sqrt(error / n)
        best = error if best is None else min(best, error)
    return best


def main():
    true_vt, true_faces, _ = read(sys.argv[1])
    out_vt, out_faces, groups = read(sys.argv[2])
    limit = float(sys.argv[3])
    if len(true_faces) != len(out_faces):
        sys.exit('face counts differ: %d and %d' % (len(true_faces), len(out_faces)))
    ratios = []
    for tf, of in zip(true_faces, out_faces):
        for k in range(3):
            t0, t1 = true_vt[tf[k]], true_vt[tf[(k + 1) % 3]]
            o0, o1 = out_vt[of[k]], out_vt[of[(k + 1) % 3]]
            true_length = math.dist(t0, t1)
            if true_length > 0:
                ratios.append(math.dist(o0, o1) / true_length)
    ratios.sort()
    scale = ratios[len(ratios) // 2]
    weighted = total_area = 0.0
    for piece in sorted(set(groups), key=lambda g: int(g.split('_')[-1])):
        a, b, area = [], [], 0.0
        for i, group in enumerate(groups):
            if group != piece:
                continue
            tri = [(true_vt[v][0] * scale, true_vt[v][1] * scale) for v in true_faces[i]]
            a += tri
            b += [out_vt[v] for v in out_faces[i]]
            (ax, ay), (bx, by), (cx, cy) = tri
            area += abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) / 2
        percent = 100 * rigid_rms(a, b) / math.sqrt(area)
        weighted += percent * area
        total_area += area
        print('%-10s %5d faces  %.2f %%' % (piece, len(a) // 3, percent))
    mean = weighted / total_area
    print('all (area-weighted) %.2f %% (limit %.2f %%)' % (mean, limit))
    sys.exit(0 if mean <= limit else 1)


main()
