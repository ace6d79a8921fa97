//! Criterion benchmarks of the THM crates live in `benches/`; peer comparisons (YADE,
//! LIGGGHTS, GeoTaichi) in `peers/NAME/`, which are never run in CI.

pub mod mpm_column {
    //! The 2D granular column-collapse case shared by the MPM bench and the CPU-time example.
    use thm_mpm::{
        Constitutive, GridParameters, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState,
        PointProperties, RigidWall,
    };

    /// A square column of `side × side` cells (2 × 2 points each) on a frictional floor against a
    /// smooth left wall, on a grid four columns wide.
    pub fn column<M: Constitutive>(side: usize, material: &M) -> (Mpm, MpmState<M::PointState>) {
        let h = 0.01;
        let mut params = MpmParameters::on_grid(GridParameters {
            origin: [0.0, 0.0],
            cell_size: h,
            cells: [4 * side + 2, side + 4],
        });
        params.gravity = [0.0, -9.81];
        params.pic_fraction = 0.05;
        params.walls = vec![
            RigidWall {
                point: [0.0, h],
                normal: [0.0, 1.0],
                velocity: [0.0; 2],
                friction: 0.5,
                removal_time: None,
                extent: None,
                depth: None,
            },
            RigidWall {
                point: [h, 0.0],
                normal: [1.0, 0.0],
                velocity: [0.0; 2],
                friction: 0.0,
                removal_time: None,
                extent: None,
                depth: None,
            },
        ];
        let config = MpmConfig::new(params).expect("valid parameters");
        let mut points = MaterialPoints::new();
        points
            .fill_rectangle(
                config.grid(),
                [h, h],
                [h * (side + 1) as f64, h * (side + 1) as f64],
                2,
                &PointProperties {
                    density: 1500.0,
                    specific_heat: 800.0,
                    conductivity: [1.0, 1.0, 0.0],
                    temperature: 20.0,
                    velocity: [0.0; 2],
                },
            )
            .expect("valid properties");
        let state = MpmState::new(points, material);
        (Mpm::new(config), state)
    }
}

pub mod pore_layer {
    //! The 10 000-circle single layer and the small motion shared by the mesh bench and the
    //! per-stage example.
    use thm_vpn_mesh::packing::{PackingSpec, random_packing};
    use thm_vpn_mesh::{Circle, CircleMotion};

    /// 10 000 circles of 4–8 mm at 10 % porosity: they fill about 0.557 m × 0.557 m, so the
    /// packing of a slightly larger square is cut to exactly 10 000.
    pub fn layer_10k() -> (Vec<Circle>, PackingSpec) {
        let side = 0.558;
        let spec = PackingSpec {
            box_max: [side, side],
            sweeps: 300,
            ..PackingSpec::paper_bar(7)
        };
        let mut cs = random_packing(&spec);
        assert!(cs.len() >= 10_000, "only {} circles", cs.len());
        cs.truncate(10_000);
        (cs, spec)
    }

    /// Every circle moved a little (tens of µm, a few mrad, 0.1 µm of growth): the circle state
    /// a geometry update between remeshes sees.
    #[derive(Debug, Clone)]
    pub struct SmallMotion {
        pub centre: Vec<[f64; 2]>,
        pub radius: Vec<f64>,
        pub velocity: Vec<[f64; 2]>,
        pub angular_velocity: Vec<f64>,
        pub radius_rate: Vec<f64>,
    }

    impl SmallMotion {
        pub fn of(cs: &[Circle]) -> Self {
            let k = cs.len();
            let velocity: Vec<[f64; 2]> = (0..k)
                .map(|i| [2e-5 * (i as f64).sin(), 2e-5 * (i as f64).cos()])
                .collect();
            let angular_velocity = (0..k).map(|i| 0.002 * (0.3 * i as f64).sin()).collect();
            let centre = cs
                .iter()
                .zip(&velocity)
                .map(|(c, v)| [c.centre[0] + v[0], c.centre[1] + v[1]])
                .collect();
            Self {
                centre,
                radius: cs.iter().map(|c| c.radius + 1e-7).collect(),
                velocity,
                angular_velocity,
                radius_rate: vec![1e-7; k],
            }
        }

        /// The circle state (the rotation since the mesh equals the angular velocity × 1 s).
        pub fn motion(&self) -> CircleMotion<'_> {
            CircleMotion {
                centre: &self.centre,
                radius: &self.radius,
                rotation: &self.angular_velocity,
                velocity: &self.velocity,
                angular_velocity: &self.angular_velocity,
                radius_rate: &self.radius_rate,
            }
        }
    }
}
