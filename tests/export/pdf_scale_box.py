#!/usr/bin/python3
# tests/export/pdf_scale_box.py -- the 10 cm scale box measured in the PDF's
# own units: its content streams (Flate-compressed by cairo) are decoded and
# searched for a rectangle (`x y w h re`) of 100 x 100 mm = 283.465 pt drawn
# where every transformation (`cm`) of that stream is a translation or a flip
# (no scaling), so the box is 283.465 pt on paper.
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
NUMBER = rb"(-?[0-9.]+)"


def streams(data):
    for match in re.finditer(rb"stream\r?\n", data):
        end = data.find(b"endstream", match.end())
        try:
            yield zlib.decompress(data[match.end():end])
        except zlib.error:
            continue


def unscaled(text):
    for a, b, c, d in re.findall(NUMBER + rb" " + NUMBER + rb" " + NUMBER + rb" " + NUMBER + rb" -?[0-9.]+ -?[0-9.]+ cm",
                                 text):
        if abs(abs(float(a)) - 1) > 1e-9 or abs(abs(float(d)) - 1) > 1e-9 or float(b) != 0 or float(c) != 0:
            return False
    return True


def main():
    data = open(sys.argv[1], "rb").read()
    for text in streams(data):
        if not unscaled(text):
            continue
        for w, h in re.findall(rb"-?[0-9.]+ -?[0-9.]+ " + NUMBER + rb" " + NUMBER + rb" re", text):
            size = (abs(float(w)) / PT_PER_MM, abs(float(h)) / PT_PER_MM)
            if abs(size[0] - 100) < 0.01 and abs(size[1] - 100) < 0.01:
                print("%s: scale box %.3f x %.3f mm" % (sys.argv[1], size[0], size[1]))
                return 0
    print("%s: no 100 x 100 mm rectangle at unit scale" % sys.argv[1])
    return 1


if __name__ == "__main__":
    sys.exit(main())
