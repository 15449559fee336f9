"""Convert the npm package 'bunny' (public domain) into Data/bunny.ply, once.

    npm pack bunny && tar xzf bunny-1.0.1.tgz
    /usr/bin/python3 Data/convert_bunny.py package/index.js Data/bunny.ply

Coordinates are scaled by 3 (lengths in mm: the bunny is about 29 mm tall).
"""
import json
import re
import sys

SCALE = 3.0
source, target = sys.argv[1], sys.argv[2]
text = open(source).read()
positions = json.loads(re.search(r"exports\.positions\s*=\s*(\[.*?\]\])", text, re.S).group(1))
cells = json.loads(re.search(r"exports\.cells\s*=\s*(\[.*?\]\])", text, re.S).group(1))
with open(target, "w") as f:
    f.write("ply\nformat ascii 1.0\n")
    f.write("comment Stanford bunny from the npm package 'bunny' 1.0.1 (public domain), "
            "scaled x3, lengths in mm\n")
    f.write(f"element vertex {len(positions)}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {len(cells)}\n"
            "property list uchar int vertex_indices\nend_header\n")
    for p in positions:
        f.write("%.6g %.6g %.6g\n" % tuple(SCALE * x for x in p))
    for c in cells:
        f.write("3 %d %d %d\n" % tuple(c))
