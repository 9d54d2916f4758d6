#!/usr/bin/python3
# tests/export/check_dxf.py -- reads pattern.dxf with ezdxf (an independent
# reader) and compares it with what panelize wrote.
#
#   check_dxf.py PATTERN.dxf EXPECTED.txt
#
# EXPECTED.txt: one line per piece: `BLOCK_NAME CUT_COUNT PERIMETER_MM
# NOTCHES LINES`. Checks: ezdxf.readfile works and doc.audit() finds no
# errors; $INSUNITS is 4 (mm); every expected block exists and is inserted
# exactly once in the model space; its closed layer-1 polyline has the cut
# line's vertex count and perimeter (1e-3 mm); a closed layer-14 polyline
# (sew line) lies inside; layer 4 holds NOTCHES lines, layer 7 one grain
# line, layer 8 LINES polylines; the text on layer 1 names the piece,
# quantity and size; the model space has the "Style Name:" text.
# Prints one line per block and exits 1 on the first failed check.
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


def main():
    path, expected_path = sys.argv[1], sys.argv[2]
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    if auditor.has_errors:
        fail("audit: %d errors: %s" % (len(auditor.errors), [str(e.message) for e in auditor.errors][:5]))
    if doc.header.get("$INSUNITS") != 4:
        fail("$INSUNITS is %r, not 4 (mm)" % doc.header.get("$INSUNITS"))
    inserts = {}
    for entity in doc.modelspace().query("INSERT"):
        inserts[entity.dxf.name] = inserts.get(entity.dxf.name, 0) + 1
    texts = [e.dxf.text for e in doc.modelspace().query("TEXT")]
    if not any(t.startswith("Style Name: ") for t in texts):
        fail("no Style Name text in the model space: %r" % texts)
    with open(expected_path) as expected:
        for line in expected:
            name, cut_count, length, notches, lines = line.split()
            if name not in doc.blocks:
                fail("block %s missing" % name)
            if inserts.get(name) != 1:
                fail("block %s inserted %d times" % (name, inserts.get(name, 0)))
            block = doc.blocks[name]
            cuts = closed_polylines(block, "1")
            if len(cuts) != 1:
                fail("block %s: %d closed polylines on layer 1" % (name, len(cuts)))
            points = [(v.dxf.location.x, v.dxf.location.y) for v in cuts[0].vertices]
            if len(points) != int(cut_count):
                fail("block %s: %d cut vertices, %s expected" % (name, len(points), cut_count))
            if abs(perimeter(points) - float(length)) > 1e-3:
                fail("block %s: cut perimeter %.6f, %s expected" % (name, perimeter(points), length))
            if len(closed_polylines(block, "14")) != 1:
                fail("block %s: no closed sew line on layer 14" % name)
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
            print("%s: %d cut vertices, perimeter %.3f mm, %d notches" % (name, len(points), perimeter(points),
                                                                        len(notch_lines)))
    print("ok: %s" % path)


if __name__ == "__main__":
    main()
