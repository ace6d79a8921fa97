#!/usr/bin/env python3
"""Converts a `dem_peer` packing CSV into a LIGGGHTS data file (atom_style granular).

    csv_to_data.py PACKING.csv DENSITY OUT.data
"""
import sys

path, density, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
spheres = []
for line in open(path):
    f = line.strip().split(',')
    if f and f[0] == 'particle':
        spheres.append(tuple(float(v) for v in f[1:5]))
lo = [min(s[k] - s[3] for s in spheres) for k in range(3)]
hi = [max(s[k] + s[3] for s in spheres) for k in range(3)]
pad = [0.05 * (h - l) + 1e-3 for l, h in zip(lo, hi)]
with open(out, 'w') as o:
    o.write('thm-dem bed\n\n%d atoms\n1 atom types\n\n' % len(spheres))
    for k, name in enumerate('xyz'):
        o.write('%.9g %.9g %slo %shi\n' % (lo[k] - pad[k], hi[k] + pad[k], name, name))
    o.write('\nAtoms\n\n')
    for i, (x, y, z, r) in enumerate(spheres, start=1):
        o.write('%d 1 %.17g %.17g %.17g %.17g %.17g\n' % (i, 2 * r, density, x, y, z))
