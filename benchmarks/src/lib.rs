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
            },
            RigidWall {
                point: [h, 0.0],
                normal: [1.0, 0.0],
                velocity: [0.0; 2],
                friction: 0.0,
                removal_time: None,
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
