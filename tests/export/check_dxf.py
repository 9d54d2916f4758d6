#!/usr/bin/python3
# tests/export/check_dxf.py -- reads pattern.dxf with ezdxf (an independent
# reader) and compares it with what panelize wrote.
#
#   check_dxf.py [--subset] PATTERN.dxf EXPECTED.txt
#
# EXPECTED.txt: one line per piece: `BLOCK_NAME CUT_COUNT CUT_PERIMETER_MM
# SEW_COUNT SEW_PERIMETER_MM NOTCHES LINES`. Checks: ezdxf.readfile works
# and doc.audit() finds no errors, and fixes nothing but the one ezdxf 0.18
# makes on every R12 POLYLINE in a block (its own R12 files included: a
# SEQEND "with invalid owner handle"); $INSUNITS is 4 (mm); every expected
# block exists (with --subset: every block of the file is expected, not
# every expected one need be there: the pattern left out the second piece
# of each mirrored pair) and is inserted exactly once in the model space;
# its closed layer-1 polyline (cut line) and closed layer-14 polyline (sew
# line) have our vertex counts and perimeters (1e-3 mm); layer 4 holds
# NOTCHES lines, layer 7 one grain line, layer 8 LINES polylines; the text
# on layer 1 names the piece, quantity and size; the model space has the
# "Style Name:" text. Prints one line per block and exits 1 on the first
# failed check.
#
# SPDX-License-Identifier: GPL-3.0-or-later
import math
import sys

import ezdxf


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def perimeter(points):
    return sum(math.dist(points[i], points[(i + 1) % len(points)]) for i in range(len(points)))


def closed_polylines(block, layer):
    return [e for e in block if e.dxftype() == "POLYLINE" and e.dxf.layer == layer and e.is_closed]


def closed_points(block, layer, name, what):
    polylines = closed_polylines(block, layer)
    if len(polylines) != 1:
        fail("block %s: %d closed polylines on layer %s (%s)" % (name, len(polylines), layer, what))
    return [(v.dxf.location.x, v.dxf.location.y) for v in polylines[0].vertices]


def check_outline(points, count, length, name, what):
    if len(points) != int(count):
        fail("block %s: %d %s vertices, %s expected" % (name, len(points), what, count))
    if abs(perimeter(points) - float(length)) > 1e-3:
        fail("block %s: %s perimeter %.6f, %s expected" % (name, what, perimeter(points), length))


def main():
    arguments = sys.argv[1:]
    subset = arguments[0] == "--subset"
    path, expected_path = arguments[1:] if subset else arguments
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    if auditor.has_errors:
        fail("audit: %d errors: %s" % (len(auditor.errors), [str(e.message) for e in auditor.errors][:5]))
    odd_fixes = [str(f.message) for f in auditor.fixes
                 if not (str(f.message).startswith("Deleted SEQEND") and "invalid owner handle" in str(f.message))]
    if odd_fixes:
        fail("audit fixed %d things: %s" % (len(odd_fixes), odd_fixes[:5]))
    if doc.header.get("$INSUNITS") != 4:
        fail("$INSUNITS is %r, not 4 (mm)" % doc.header.get("$INSUNITS"))
    inserts = {}
    for entity in doc.modelspace().query("INSERT"):
        inserts[entity.dxf.name] = inserts.get(entity.dxf.name, 0) + 1
    texts = [e.dxf.text for e in doc.modelspace().query("TEXT")]
    if not any(t.startswith("Style Name: ") for t in texts):
        fail("no Style Name text in the model space: %r" % texts)
    expected = {}
    with open(expected_path) as lines:
        for line in lines:
            fields = line.split()
            expected[fields[0]] = fields[1:]
    pieces = [b.name for b in doc.blocks if not b.name.startswith("*")]
    for name in pieces:
        if name not in expected:
            fail("block %s is not one of our pieces" % name)
    if not subset:
        for name in expected:
            if name not in doc.blocks:
                fail("block %s missing" % name)
    for name in pieces:
        cut_count, cut_length, sew_count, sew_length, notches, lines = expected[name]
        if inserts.get(name) != 1:
            fail("block %s inserted %d times" % (name, inserts.get(name, 0)))
        block = doc.blocks[name]
        cut = closed_points(block, "1", name, "cut line")
        check_outline(cut, cut_count, cut_length, name, "cut")
        check_outline(closed_points(block, "14", name, "sew line"), sew_count, sew_length, name, "sew")
        notch_lines = [e for e in block if e.dxftype() == "LINE" and e.dxf.layer == "4"]
        grain = [e for e in block if e.dxftype() == "LINE" and e.dxf.layer == "7"]
        internal = [e for e in block if e.dxftype() == "POLYLINE" and e.dxf.layer == "8"]
        if len(notch_lines) != int(notches) or len(grain) != 1 or len(internal) != int(lines):
            fail("block %s: %d notches (%s), %d grain lines, %d internal lines (%s)"
                 % (name, len(notch_lines), notches, len(grain), len(internal), lines))
        labels = [e.dxf.text for e in block if e.dxftype() == "TEXT" and e.dxf.layer == "1"]
        for key in ("Piece Name: ", "Quantity: ", "Size: "):
            if not any(t.startswith(key) for t in labels):
                fail("block %s: no '%s' text in %r" % (name, key, labels))
        print("%s: %d cut vertices, perimeter %.3f mm, %d notches" % (name, len(cut), perimeter(cut),
                                                                    len(notch_lines)))
    print("ok: %s (%d pieces)" % (path, len(pieces)))


if __name__ == "__main__":
    main()
