# Runs the A-Table 1 cohesive law (CohFrictMat) on a packing written by `dem_peer write-*`
# and prints "particles steps seconds particle_steps_per_second", like `dem_peer run-cohesive`.
#
#   yade -n -x yade_cohesive.py PACKING.csv STEPS DT [SPEED]
#
# With SPEED [m/s], the loaded case of `dem_peer run-pull`: the spheres whose surface lies
# within the largest radius of the lowest or highest surface along y are held (all degrees of
# freedom blocked) and move apart at SPEED each (bottom -y, top +y); the script then also
# prints "broken_bonds N" (bonds of the file no longer intact after the timed steps),
# "free_kinetic_energy E" (the spheres not held) and "top_grip_force_y F" (the y resultant of
# the contact forces on the top grip).
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
speed = float(sys.argv[4]) if len(sys.argv) > 4 else None
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

top_grip, grips = [], set()
if speed is not None:  # the grips, selected as dem_peer's pull_apart does
    depth = max(r for (_, _, _, r) in spheres)
    bottom = min(y - r for (_, y, _, r) in spheres)
    top = max(y + r for (_, y, _, r) in spheres)
    for k, (x, y, z, r) in enumerate(spheres):
        if y - r < bottom + depth:
            v = -speed
        elif y + r > top - depth:
            v = speed
            top_grip.append(ids[k])
        else:
            continue
        grips.add(ids[k])
        s = O.bodies[ids[k]].state
        s.blockedDOFs = 'xyzXYZ'
        s.vel = (0.0, v, 0.0)
        s.angVel = (0.0, 0.0, 0.0)

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
if speed is not None:
    print('broken_bonds %d' % (len(bonds) - intact))
    free = 0.0
    for b in O.bodies:
        if b.id in grips:
            continue
        s = b.state
        free += 0.5 * s.mass * s.vel.squaredNorm() + 0.5 * s.inertia[0] * s.angVel.squaredNorm()
    print('free_kinetic_energy %.9e' % free)
    print('top_grip_force_y %.9e' % sum(O.forces.f(i)[1] for i in top_grip))
