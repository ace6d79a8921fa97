# Runs the A-Table 1 cohesive law (CohFrictMat) on a packing written by `dem_peer write-*`
# and prints "particles steps seconds particle_steps_per_second", like `dem_peer run-cohesive`.
#
#   yade -n -x yade_cohesive.py PACKING.csv STEPS DT
#
# Bonds are created exactly for the file's bond list and made stress-free at creation
# (YADE's bonds otherwise have their zero-force point at touching, and a bond across a gap
# breaks at once). Timing is a loop of single steps: O.run(n, True) returns on a ~40 ms grid.
import math
import sys
import time

from yade import O, utils
from yade.wrapper import (CohFrictMat, ForceResetter, InsertionSortCollider, Bo1_Sphere_Aabb,
                          InteractionLoop, Ig2_Sphere_Sphere_ScGeom6D,
                          Ip2_CohFrictMat_CohFrictMat_CohFrictPhys,
                          Law2_ScGeom6D_CohFrictPhys_CohesionMoment, NewtonIntegrator)

path, steps, dt = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
kinematics, spheres, bonds = None, [], []
for line in open(path):
    line = line.strip()
    if line.startswith('#'):
        if 'kinematics=' in line:
            kinematics = line.split('kinematics=')[1].strip()
        continue
    if not line or line.startswith('kind,'):
        continue
    f = line.split(',')
    if f[0] == 'particle':
        spheres.append((float(f[1]), float(f[2]), float(f[3]), float(f[4])))
    elif f[0] == 'bond':
        bonds.append((int(f[1]), int(f[2])))

T, C = 30e6, 150e6
mat = O.materials.append(CohFrictMat(young=3.36e9, poisson=0.3, frictionAngle=math.radians(18.0),
                                     density=2600.0, normalCohesion=T, shearCohesion=C,
                                     momentRotationLaw=False, isCohesive=True, fragile=True))
ids = []
for (x, y, z, r) in spheres:
    b = utils.sphere((x, y, z), r, material=mat)
    if kinematics in ('spheres_in_plane', 'disks'):
        b.state.blockedDOFs = 'zXY'
    ids.append(O.bodies.append(b))

# Largest gap bridged by a bond, as a factor on the radii sum, for detection and geometry.
factor = 1.0
for (a, b) in bonds:
    (xa, ya, za, ra), (xb, yb, zb, rb) = spheres[a], spheres[b]
    d = math.sqrt((xb - xa) ** 2 + (yb - ya) ** 2 + (zb - za) ** 2)
    factor = max(factor, 1.01 * d / (ra + rb))

ig2 = Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=factor)
bo1 = Bo1_Sphere_Aabb(aabbEnlargeFactor=factor)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([bo1]),
    InteractionLoop([ig2], [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys()],
                    [Law2_ScGeom6D_CohFrictPhys_CohesionMoment()]),
    NewtonIntegrator(damping=0.08),
]
O.dt = dt
for (a, b) in bonds:  # before the first step, so no interaction exists yet
    i = utils.createInteraction(ids[a], ids[b])
    rmin = min(spheres[a][3], spheres[b][3])
    i.phys.cohesionBroken = False
    i.phys.normalAdhesion = T * rmin ** 2
    i.phys.shearAdhesion = C * rmin ** 2
    i.phys.unp = i.geom.penetrationDepth  # stress-free at its creation distance
# Back to the detection range of touching spheres for new contacts.
ig2.interactionDetectionFactor = 1.0
bo1.aabbEnlargeFactor = 1.0

O.step()
max_fn = max([abs(i.phys.normalForce.norm()) for i in O.interactions if i.isReal] or [0.0])
t0 = time.perf_counter()
for _ in range(steps):
    O.step()
seconds = time.perf_counter() - t0
intact = sum(1 for i in O.interactions if i.isReal and not i.phys.cohesionBroken)
print('bonds intact %d of %d; largest normal force after the first step %.3g N' % (intact, len(bonds), max_fn))
print('%d %d %.6f %.1f' % (len(ids), steps, seconds, len(ids) * steps / seconds))
# The same observable as dem_peer's: translational + rotational kinetic energy after the timed
# steps [J], so a run shows both codes did the same physics.
print('kinetic_energy %.9e' % utils.kineticEnergy())
