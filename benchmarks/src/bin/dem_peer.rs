//! Our side of the peer comparisons in `benchmarks/peers/` (YADE, LIGGGHTS).
//!
//! ```text
//! dem_peer write-bar FILE SEED            # the A-Sect. 3 bar (random packing, bonds ≤ 4 mm)
//! dem_peer write-lattice FILE N PLANE|3D [APART]  # bonded lattice of about N particles
//! dem_peer write-bed FILE N               # settled frictional bed of about N spheres (3D)
//! dem_peer run-cohesive FILE STEPS DT THREADS   # A-Table 1 law, α_d = 0.08, like CohFrictMat
//! dem_peer run-pull FILE STEPS DT THREADS SPEED # the same, pulled apart along y (below)
//! dem_peer run-bed FILE STEPS DT THREADS        # linear spring + Coulomb, gravity, floor
//! ```
//!
//! A `run-*` command followed by `--locality-order` renumbers the particles of the file with
//! [`Packing::in_locality_order`] before the run (untimed, as LIGGGHTS sorts its atoms in the
//! set-up of a run; it prints `locality_order_seconds S` last).
//!
//! `run-*` prints `particles steps seconds particle_steps_per_second` on its first line (the
//! timed steps only, after one untimed step), then two lines that let a run be checked against
//! the peer's:
//!
//! ```text
//! neighbour_builds B     # neighbour-list builds (Verlet searches) during the timed steps
//! kinetic_energy E       # total kinetic energy after them, translational + rotational [J]
//! ```
//!
//! `run-pull` is `run-cohesive` with the particles whose surface lies within their largest
//! radius of the lowest or highest surface along y held (fixed) and moving apart at
//! `SPEED` m/s each (bottom −y, top +y) from the start: a loaded case, stress waves, bonds
//! breaking in tension and shear, new frictional contacts. It also prints `broken_bonds N`
//! (bonds of the file no longer intact after the timed steps), `free_kinetic_energy E` (that of
//! the particles not held, the part of the kinetic energy the held ones do not dictate) and
//! `top_grip_force_y F` (the y resultant of the contact forces on the top grip \[N\]).

use std::path::Path;
use std::time::Instant;
use thm_dem::packing::{Packing, PackingParams, lattice_packing, random_packing};
use thm_dem::*;

/// Stiffness, friction and density of the bed (the LIGGGHTS script uses the same numbers).
const BED_KN: f64 = 2.0e5;
const BED_KT: f64 = 0.5e5;
const BED_MU: f64 = 0.5;
const BED_DENSITY: f64 = 2500.0;
const BED_SPACING: f64 = 1.0e-3;

fn main() {
    if let Err(e) = run() {
        eprintln!("dem_peer: {e}");
        std::process::exit(1);
    }
}

fn arg<T: std::str::FromStr>(args: &[String], i: usize, what: &str) -> Result<T, String> {
    args.get(i)
        .ok_or(format!("missing {what}"))?
        .parse()
        .map_err(|_| format!("bad {what}: {}", args[i]))
}

fn run() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().collect();
    let flag = "--locality-order";
    let locality_order = args.iter().any(|a| a == flag);
    args.retain(|a| a != flag);
    let cmd = args.get(1).map(String::as_str).unwrap_or("");
    match cmd {
        "write-bar" => {
            let seed: u64 = arg(&args, 3, "SEED")?;
            let params = PackingParams {
                bond_gap: 4e-3,
                ..PackingParams::paper_a_bar(seed)
            };
            let (p, _) = random_packing(&params, 2600.0).map_err(|e| e.to_string())?;
            p.write_csv(Path::new(&args[2])).map_err(|e| e.to_string())
        }
        "write-lattice" => {
            let n: usize = arg(&args, 3, "N")?;
            let plane = args.get(4).map(String::as_str) != Some("3D");
            let kin = if plane {
                Kinematics::SpheresInPlane
            } else {
                Kinematics::Spheres3d
            };
            let counts = if plane {
                let side = (n as f64).sqrt().round() as usize;
                [side, side, 1]
            } else {
                let side = (n as f64).cbrt().round() as usize;
                [side, side, side]
            };
            let mut p = lattice_packing(kin, counts, 1e-3, 42).map_err(|e| e.to_string())?;
            if args.get(5).map(String::as_str) == Some("APART") {
                separate(&mut p);
            }
            p.write_csv(Path::new(&args[2])).map_err(|e| e.to_string())
        }
        "write-bed" => {
            let n: usize = arg(&args, 3, "N")?;
            write_bed(Path::new(&args[2]), n)
        }
        "run-cohesive" | "run-bed" | "run-pull" => {
            let mut packing = Packing::read_csv(Path::new(args.get(2).ok_or("missing FILE")?))
                .map_err(|e| e.to_string())?;
            let renumbering = locality_order.then(|| {
                let start = Instant::now();
                packing = packing.in_locality_order().0;
                start.elapsed().as_secs_f64()
            });
            let steps: u64 = arg(&args, 3, "STEPS")?;
            let dt: f64 = arg(&args, 4, "DT")?;
            let threads: usize = arg(&args, 5, "THREADS")?;
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| e.to_string())?;
            let mut pulled = None;
            let timed = if cmd == "run-cohesive" || cmd == "run-pull" {
                let mut state = packing
                    .to_state(2600.0, 293.15)
                    .map_err(|e| e.to_string())?;
                let grips = if cmd == "run-pull" {
                    let speed: f64 = arg(&args, 6, "SPEED")?;
                    Some(pull_apart(&mut state, speed))
                } else {
                    None
                };
                let law = CohesiveFrictionalParams::paper_a_table_1()
                    .validate()
                    .map_err(|e| e.to_string())?;
                let params = StepperParams {
                    time_step: dt,
                    damping: 0.08,
                    gravity: [0.0; 3],
                    verlet_skin: 2e-4,
                };
                let timed = time_run(&pool, &mut state, law, params, steps)?;
                if let Some([_, top]) = grips {
                    let p = &state.particles;
                    let free_kinetic_energy: f64 = (0..p.len())
                        .filter(|&i| !p.fixed[i])
                        .map(|i| {
                            0.5 * p.mass[i] * p.velocity[i].norm_squared()
                                + 0.5 * p.inertia[i] * p.angular_velocity[i].norm_squared()
                        })
                        .sum();
                    pulled = Some((
                        // Bonds of the file no longer intact (as the YADE script counts them).
                        packing
                            .bonds
                            .len()
                            .saturating_sub(state.contacts.intact_bond_count()),
                        free_kinetic_energy,
                        p.resultant_force(&top).y,
                    ));
                }
                timed
            } else {
                let mut state = bed_state(&packing)?;
                let law = bed_law()?;
                let params = StepperParams {
                    time_step: dt,
                    damping: 0.0,
                    gravity: [0.0, 0.0, -9.81],
                    verlet_skin: 1e-4,
                };
                time_run(&pool, &mut state, law, params, steps)?
            };
            let Timed {
                particles: n,
                seconds,
                builds,
                kinetic_energy,
                listed,
                active,
            } = timed;
            println!(
                "{n} {steps} {seconds:.6} {:.1}",
                n as f64 * steps as f64 / seconds
            );
            println!("neighbour_builds {builds}");
            println!("kinetic_energy {kinetic_energy:.9e}");
            println!("listed_pairs {listed} active_pairs {active}");
            if let Some((broken, free_kinetic_energy, top_force)) = pulled {
                println!("broken_bonds {broken}");
                println!("free_kinetic_energy {free_kinetic_energy:.9e}");
                println!("top_grip_force_y {top_force:.9e}");
            }
            if let Some(seconds) = renumbering {
                println!("locality_order_seconds {seconds:.6}");
            }
            Ok(())
        }
        _ => Err("usage: see the module documentation of benchmarks/src/bin/dem_peer.rs".into()),
    }
}

/// What a timed run reports.
struct Timed {
    particles: usize,
    seconds: f64,
    /// Neighbour-list builds during the timed steps.
    builds: u64,
    /// Total kinetic energy after the timed steps \[J\].
    kinetic_energy: f64,
    /// Listed particle pairs and those that carried force in the last step.
    listed: usize,
    active: usize,
}

fn time_run<L: ContactLaw>(
    pool: &rayon::ThreadPool,
    state: &mut DemState,
    law: L,
    params: StepperParams,
    steps: u64,
) -> Result<Timed, String> {
    let mut stepper = Stepper::new(law, params.validate().map_err(|e| e.to_string())?);
    pool.install(|| stepper.step(state))
        .map_err(|e| e.to_string())?;
    // Each neighbour search increments the contact generation once; nothing else in these
    // runs does (no caller edits the contact lists), so the difference counts the builds
    // without touching the timed loop.
    let generation = state.contact_generation;
    let t0 = Instant::now();
    pool.install(|| stepper.run(state, steps))
        .map_err(|e| e.to_string())?;
    let seconds = t0.elapsed().as_secs_f64();
    Ok(Timed {
        particles: state.particles.len(),
        seconds,
        builds: state.contact_generation - generation,
        kinetic_energy: state.particles.kinetic_energy(),
        listed: state.contacts.len(),
        active: state.contacts.active_count(),
    })
}

/// Scales every radius by one factor so that the closest bonded pair just touches and no
/// bonded pair overlaps. The loaded comparison needs it: YADE's fragile CohFrictPhys forgets a
/// bond's stress-free offset when the bond breaks, so a pair bonded while overlapping is
/// pushed apart by its whole overlap the moment it breaks (energy from nowhere), whereas
/// `thm-dem` keeps the offset; without overlaps the two agree.
fn separate(p: &mut Packing) {
    let factor = p
        .bonds
        .iter()
        .map(|&(a, b)| (p.centres[a] - p.centres[b]).norm() / (p.radii[a] + p.radii[b]))
        .fold(1.0_f64, f64::min);
    for r in &mut p.radii {
        *r *= factor;
    }
}

/// Holds the particles within their largest radius of the lowest and highest surfaces along
/// y and moves them apart at `speed` \[m/s\] each (the YADE script selects the same ones);
/// returns the two grips.
fn pull_apart(state: &mut DemState, speed: f64) -> [Vec<usize>; 2] {
    let p = &mut state.particles;
    let depth = p.radius.iter().copied().fold(0.0_f64, f64::max);
    let bottom = (0..p.len())
        .map(|i| p.position[i].y - p.radius[i])
        .fold(f64::INFINITY, f64::min);
    let top = (0..p.len())
        .map(|i| p.position[i].y + p.radius[i])
        .fold(f64::NEG_INFINITY, f64::max);
    let grips = p.near_ends(bottom, top, depth);
    for (ends, v) in grips.iter().zip([-speed, speed]) {
        for &i in ends {
            p.fixed[i] = true;
            p.velocity[i] = Vec3::new(0.0, v, 0.0);
        }
    }
    grips
}

fn bed_law() -> Result<LinearSpring, String> {
    LinearSpringParams {
        normal_stiffness: BED_KN,
        tangential_stiffness: BED_KT,
        friction_coefficient: BED_MU,
        thermal_bond: None,
    }
    .validate()
    .map_err(|e| e.to_string())
}

fn bed_state(p: &Packing) -> Result<DemState, String> {
    let particles = ParticleState::new(
        Kinematics::Spheres3d,
        BED_DENSITY,
        293.15,
        &p.centres,
        &p.radii,
    )
    .map_err(|e| e.to_string())?;
    let floor = Wall::new(
        Vec3::new(0.0, 0.0, -0.5 * BED_SPACING),
        Vec3::new(0.0, 0.0, 1.0),
    )
    .map_err(|e| e.to_string())?;
    Ok(DemState::new(particles, vec![floor]))
}

/// A jittered lattice of spheres (radius 0.40–0.45 mm, spacing 1 mm, square footprint,
/// ~N/side² layers, every other layer shifted by half a spacing in x and y so that each sphere
/// falls into the pocket between four below it instead of onto a column), dropped onto a floor
/// between four side walls and settled with damping, then written without bonds. Fails unless
/// the bed has settled (coordination ≥ 3).
fn write_bed(path: &Path, n: usize) -> Result<(), String> {
    let side = ((n as f64) / 10.0).sqrt().round().max(1.0) as usize;
    let layers = n.div_ceil(side * side);
    let lattice = lattice_packing(Kinematics::Spheres3d, [side, side, layers], BED_SPACING, 7)
        .map_err(|e| e.to_string())?;
    // Radii 0.8 × [0.5, 0.56] spacing: no two spheres of the jittered lattice touch at the start
    // (largest diameter 0.9 mm, nearest centres 0.96 mm apart), so nothing starts compressed.
    let mut centres = Vec::with_capacity(lattice.centres.len());
    let mut radii = Vec::with_capacity(lattice.centres.len());
    let last = (side as f64 - 1.0) * BED_SPACING;
    for (c, r) in lattice.centres.iter().zip(&lattice.radii) {
        let layer = (c.z / BED_SPACING).round() as usize;
        let mut c = *c;
        if layer % 2 == 1 {
            c.x += 0.5 * BED_SPACING;
            c.y += 0.5 * BED_SPACING;
            if c.x > last + 0.1 * BED_SPACING || c.y > last + 0.1 * BED_SPACING {
                continue;
            }
        }
        centres.push(c);
        radii.push(0.8 * r);
    }
    let packing = Packing {
        kinematics: Kinematics::Spheres3d,
        centres,
        radii,
        bonds: Vec::new(),
    };
    let mut state = bed_state(&packing)?;
    let lo = -0.5 * BED_SPACING;
    let hi = (side as f64 - 0.5) * BED_SPACING;
    for (point, normal) in [
        (Vec3::new(lo, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)),
        (Vec3::new(hi, 0.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)),
        (Vec3::new(0.0, lo, 0.0), Vec3::new(0.0, 1.0, 0.0)),
        (Vec3::new(0.0, hi, 0.0), Vec3::new(0.0, -1.0, 0.0)),
    ] {
        state
            .walls
            .push(Wall::new(point, normal).map_err(|e| e.to_string())?);
    }
    let law = bed_law()?;
    let dt = 0.3 * critical_time_step(&state, &law);
    // The lattice's layers stand up to 0.16 mm apart: under 1 g the top layer would need
    // ~14 ms (~3·10⁴ steps) of free fall alone to land. Pack it first under 100 g (the weight of
    // ten layers then compresses the bottom contacts by ~5·10⁻⁸ m, 10⁻⁴ of a radius), then let it
    // relax under 1 g, both with Cundall damping, until it is at rest and every sphere rests on
    // others: a settled bed, whose contacts are what the run times.
    for (gravity, damping, steps) in [(100.0 * 9.81, 0.3, 20_000), (9.81, 0.6, 40_000)] {
        let params = StepperParams {
            time_step: dt,
            damping,
            gravity: [0.0, 0.0, -gravity],
            verlet_skin: 1e-4,
        };
        let mut stepper = Stepper::new(law, params.validate().map_err(|e| e.to_string())?);
        stepper.run(&mut state, steps).map_err(|e| e.to_string())?;
    }
    let max_speed = state
        .particles
        .velocity
        .iter()
        .map(|v| v.norm())
        .fold(0.0_f64, f64::max);
    let z = state.coordination_number();
    let fast = state
        .particles
        .velocity
        .iter()
        .filter(|v| v.norm() > 1e-2)
        .count();
    let (zmin, zmax) = state
        .particles
        .position
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.z), b.max(p.z)));
    eprintln!(
        "bed settled: coordination {z:.2}, largest speed {max_speed:.2e} m/s, {fast} faster than 1 cm/s, z {zmin:e}..{zmax:e}"
    );
    if z < 3.0 {
        return Err(format!(
            "bed did not settle: coordination {z:.2} < 3 after 60 000 steps"
        ));
    }
    let settled = Packing {
        kinematics: Kinematics::Spheres3d,
        centres: state.particles.position.clone(),
        radii: state.particles.radius.clone(),
        bonds: Vec::new(),
    };
    settled.write_csv(path).map_err(|e| e.to_string())?;
    eprintln!(
        "bed: {} spheres, {side}×{side} footprint, dt_crit-based step {dt:e} s",
        settled.radii.len()
    );
    Ok(())
}
