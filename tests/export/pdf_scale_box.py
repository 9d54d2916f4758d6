#!/usr/bin/python3
# tests/export/pdf_scale_box.py -- the 10 cm scale box measured in the PDF's
# own units: its content streams (Flate-compressed by cairo) are decoded and
# searched for a rectangle (`x y w h re`) of 100 x 100 mm = 283.465 pt drawn
# where the transformation in effect (the `cm`s saved and restored by q and Q)
# is a translation, a flip or a quarter turn (no scaling), so the box is
# 283.465 pt on paper.
#
#   pdf_scale_box.py FILE.pdf
#
# Prints the box's size in mm and exits 0 when found (within 0.01 mm), 1
# otherwise. Standard library only (re, zlib).
#
# SPDX-License-Identifier: GPL-3.0-or-later
import re
import sys
import zlib

PT_PER_MM = 72 / 25.4


def streams(data):
    for match in re.finditer(rb"stream\r?\n", data):
        end = data.find(b"endstream", match.end())
        try:
            yield zlib.decompress(data[match.end():end])
        except zlib.error:
            continue


def rectangles(text):
    """Every `re` with the transformation (`cm`, saved by q, restored by Q) in effect where it is drawn."""
    stack, ctm, operands = [], (1.0, 0.0, 0.0, 1.0), []
    for token in re.findall(rb"-?[0-9]*\.?[0-9]+|[A-Za-z*'\"]+", text):
        if re.match(rb"-?[0-9]*\.?[0-9]+$", token):
            operands.append(float(token))
            continue
        if token == b"q":
            stack.append(ctm)
        elif token == b"Q" and stack:
            ctm = stack.pop()
        elif token == b"cm" and len(operands) >= 6:
            a, b, c, d = operands[-6:-2]
            m = ctm
            ctm = (a * m[0] + b * m[2], a * m[1] + b * m[3], c * m[0] + d * m[2], c * m[1] + d * m[3])
        elif token == b"re" and len(operands) >= 4:
            yield operands[-2], operands[-1], ctm
        operands = []


def unscaled(ctm):
    """A translation, a flip or a quarter turn: lengths on paper are the stream's."""
    a, b, c, d = ctm
    straight = abs(abs(a) - 1) < 1e-9 and abs(abs(d) - 1) < 1e-9 and b == 0 and c == 0
    turned = abs(abs(b) - 1) < 1e-9 and abs(abs(c) - 1) < 1e-9 and a == 0 and d == 0
    return straight or turned


def main():
    data = open(sys.argv[1], "rb").read()
    for text in streams(data):
        for w, h, ctm in rectangles(text):
            if not unscaled(ctm):
                continue
            size = (abs(w) / PT_PER_MM, abs(h) / PT_PER_MM)
            if abs(size[0] - 100) < 0.01 and abs(size[1] - 100) < 0.01:
                print("%s: scale box %.3f x %.3f mm" % (sys.argv[1], size[0], size[1]))
                return 0
    print("%s: no 100 x 100 mm rectangle at unit scale" % sys.argv[1])
    return 1


if __name__ == "__main__":
    sys.exit(main())
