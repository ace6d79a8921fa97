"""GeoTaichi 0.2.6 (CPU backend) on the granular column collapse of `thm_benchmarks::mpm_column`.

    python geotaichi_column.py SIDE THREADS STEPS [WARMUP=10]

Builds the same column as `mpm_column::column(SIDE, ..)` (a square of SIDE x SIDE cells of
h = 0.01 m, 2 x 2 points per cell, on a grid of (4 SIDE + 2) x (SIDE + 4) cells, a frictional
floor at y = h, a smooth wall at x = h), as a plane-strain slab one cell thick (0.2.6 builds 3D
bodies only): one point per cell across the slab, and every node held at v_z = 0. Runs WARMUP
steps (they include the JIT compilation of every kernel), then times STEPS more and prints

    RESULT <points> <threads> <point-steps/s wall> <point-steps per CPU-second>

The GeoTaichi wheel's `geotaichi` package is broken (`from ..src import *`), so its top-level
`src` package is imported and `taichi.init` is called here as `geotaichi.init(arch="cpu", ..)`
would.
"""
import contextlib
import io
import os
import sys
import tempfile
import time

import numpy as np
import taichi as ti

SIDE, THREADS, STEPS = (int(a) for a in sys.argv[1:4])
WARMUP = int(sys.argv[4]) if len(sys.argv) > 4 else 10

ti.init(arch=ti.cpu, cpu_max_num_threads=THREADS, default_fp=ti.f64, default_ip=ti.i32,
        offline_cache=True, debug=False, log_level=ti.ERROR)

from src.mpm.mainMPM import MPM  # noqa: E402  (after ti.init, as GeoTaichi requires)
from src.mpm.generator.LoadFromFile import BodyReader  # noqa: E402

# 0.2.6 rotates every body read from a file about its centre, even for the identity
# orientation, and that kernel does not compile (`body_coords[nb, 0] = coords` stores a vector
# in a scalar). The orientation here is the identity: skip the rotation.
BodyReader.rotate_body = lambda self, orientation, coords, start, count: None

H = 0.01                      # cell size (m)
DT = 1e-4                     # time step (s)
CELLS = (4 * SIDE + 2, SIDE + 4, 1)
# GeoTaichi counts nodes as int(domain / h) + 1: pad so that round-off cannot drop a node.
DOMAIN = [(n + 1e-6) * H for n in CELLS]

# Points: 2 x 2 per cell in the plane at the quarter points, one at mid-thickness; uGIMP
# half-sizes h/4 in the plane (as ours) and h/4 across (weights 1/2 on both node layers).
q = (np.arange(2 * SIDE) + 0.5) * (H / 2) + H
xs, ys = np.meshgrid(q, q, indexing="ij")
n = xs.size
points = np.column_stack([xs.ravel(), ys.ravel(), np.full(n, H / 2),
                          np.full(n, (H / 2) * (H / 2) * H),
                          np.full(n, H / 4), np.full(n, H / 4), np.full(n, H / 4)])

work = tempfile.mkdtemp(prefix="geotaichi-column-")
pfile = os.path.join(work, "points.txt")
np.savetxt(pfile, points)

quiet = io.StringIO()
with contextlib.redirect_stdout(quiet):
    mpm = MPM(log=False)
    mpm.set_configuration(log=False, domain=ti.Vector(DOMAIN), dimension="3-Dimension",
                          boundary=["Destroy", "Destroy", "Destroy"],
                          gravity=ti.Vector([0.0, -9.81, 0.0]), background_damping=0.0,
                          alphaPIC=0.05, mapping="USL", shape_function="GIMP")
    mpm.set_solver(log=False, solver={"Timestep": DT, "SimulationTime": 1.0, "CFL": 1.0,
                                      "SaveInterval": 1e9, "SavePath": os.path.join(work, "out")})
    nodes = [c + 1 for c in CELLS]
    mpm.memory_allocate(log=False, memory={
        "max_material_number": 1,
        "max_particle_number": n,
        "max_constraint_number": {
            "max_velocity_constraint": nodes[0] * nodes[1] * nodes[2],
            "max_friction_constraint": nodes[0] * 2 * nodes[2],
            "max_reflection_constraint": 2 * nodes[1] * nodes[2],
        },
    })
    mpm.add_material(model="DruckerPrager", material={
        "MaterialID": 1, "Density": 1500.0, "YoungModulus": 1e6, "PossionRatio": 0.3,
        "Cohesion": 0.0, "Friction": 30.0, "Dilation": 0.0, "Tensile": 0.0,
        # The cone matched to Mohr-Coulomb in plane strain, as ours:
        # q = 3 tan(phi) / sqrt(9 + 12 tan^2 phi) on the mean stress = alpha on I1.
        "dpType": "Inscribed",
    })
    mpm.add_element(element={"ElementType": "R8N3D", "ElementSize": ti.Vector([H, H, H])})
    mpm.add_body_from_file(body={"FileType": "TXT", "Template": {
        "ParticleFile": pfile, "BodyID": 0, "MaterialID": 1, "ParticleNumber": n,
        "ParticleStress": {"GravityField": False, "InternalStress": ti.Vector([0.0] * 6)},
        "InitialVelocity": [0.0, 0.0, 0.0], "FixVelocity": ["Free", "Free", "Free"]}})
    # 0.2.6 reads the point sizes from the file but never hands them to the GIMP kernels (the
    # body's characteristic length stays 0, i.e. linear hats): set it here.
    mpm.scene.element.calLength[0] = ti.Vector([H / 4, H / 4, H / 4])
    top = [DOMAIN[0], DOMAIN[1], DOMAIN[2]]
    mpm.add_boundary_condition(boundary=[
        # Plane strain: no velocity across the slab, anywhere.
        {"BoundaryType": "VelocityConstraint", "VelocityZ": 0.0,
         "StartPoint": ti.Vector([0.0, 0.0, 0.0]), "EndPoint": ti.Vector(top)},
        # Floor at y = h (nodes on or below it), Coulomb friction 0.5, outward normal -y.
        {"BoundaryType": "FrictionConstraint", "Friction": 0.5, "Norm": ti.Vector([0.0, -1.0, 0.0]),
         "StartPoint": ti.Vector([0.0, 0.0, 0.0]), "EndPoint": ti.Vector([top[0], H, top[2]])},
        # Smooth wall at x = h (nodes on or left of it), outward normal -x.
        {"BoundaryType": "ReflectionConstraint", "Norm": ti.Vector([-1.0, 0.0, 0.0]),
         "StartPoint": ti.Vector([0.0, 0.0, 0.0]), "EndPoint": ti.Vector([H, top[1], top[2]])},
    ])
    mpm.add_essentials({})
    mpm.check_critical_timestep()
    solver, scene, neighbor, sims = mpm.solver, mpm.scene, mpm.neighbor, mpm.sims
    solver.engine.pre_calculation(sims, scene, neighbor)

assert abs(sims.dt[None] - DT) < 1e-15, f"time step changed to {sims.dt[None]}"
assert int(scene.particleNum[0]) == n


def advance(steps):
    for _ in range(steps):
        solver.core(scene, neighbor)
        sims.current_time += sims.delta
        sims.current_step += 1
    ti.sync()


y0 = scene.particle.x.to_numpy()[:n, 1].mean()
advance(WARMUP)
w0, c0 = time.perf_counter(), time.process_time()
advance(STEPS)
wall, cpu = time.perf_counter() - w0, time.process_time() - c0

x = scene.particle.x.to_numpy()[:n]
v = scene.particle.v.to_numpy()[:n]
if not (np.isfinite(x).all() and np.isfinite(v).all()):
    sys.exit("non-finite point positions or velocities")
if np.abs(x[:, 2] - H / 2).max() > 1e-12:
    sys.exit("points left the mid-plane: not plane strain")
print(f"# geotaichi {n} pts {THREADS}t: {WARMUP + STEPS} steps, centre of mass dropped "
      f"{1e3 * (y0 - x[:, 1].mean()):.4f} mm, max |v| {np.abs(v).max():.4f} m/s", file=sys.stderr)
print(f"RESULT {n} {THREADS} {n * STEPS / wall:.6g} {n * STEPS / cpu:.6g}")
