//! Numerical stability on stiff and extreme cases: each runs at least 1e4 steps with the automatic
//! time step and must neither diverge nor gain energy.
//!
//! "Bounded energy": without actuation the body only loses energy (damping, friction) once placed,
//! so the total energy may not rise above its start by more than 0.1 % of the gravitational
//! energy of lifting the body by half a voxel (room for the O(ω dt) wobble of the symplectic
//! integrator's shadow energy). With actuation, energy is pumped in, so the bound is on speed:
//! no voxel faster than what a stable response to the actuation allows (three times its surface
//! speed, derived at the test).

use amorph::dynamics::{Actuation, DampingParams, DynamicScene, Pass, Simulation};
use amorph::material::{Material, MaterialId, Palette};
use amorph::voxel::{GridDims, VoxelGrid};

const MIN_STEPS: u64 = 10_000;

fn material(e: f64, actuated: bool) -> Material {
    let mut m = Material::new(if actuated { "active" } else { "passive" }, e, 0.35);
    m.actuated = actuated;
    m
}

fn run_passive(grid: &VoxelGrid, palette: &Palette, scene: &DynamicScene, min_time: f64) -> u64 {
    let mut sim = Simulation::new(grid, palette, scene).unwrap();
    let start = sim.energy().total();
    let body_mass = grid.filled_count() as f64 * 1000.0 * scene.voxel_size.powi(3);
    let allowance = 1e-3 * body_mass * scene.gravity.max(1.0) * 0.5 * scene.voxel_size;
    let steps = MIN_STEPS.max((min_time / sim.dt()).ceil() as u64);
    let mut worst = f64::NEG_INFINITY;
    for k in 0..steps {
        if let Err(d) = sim.step() {
            panic!("diverged: {d}");
        }
        if k % 97 == 0 {
            worst = worst.max(sim.energy().total() - start);
        }
    }
    assert!(
        worst <= allowance,
        "energy rose by {worst} J (allowed {allowance})"
    );
    steps
}

fn block(n: [usize; 3], material_of: impl Fn(usize, usize, usize) -> u8) -> VoxelGrid {
    let dims = GridDims::new(n[0], n[1], n[2]);
    let mut grid = VoxelGrid::empty(dims);
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                grid.set(x, y, z, Some(MaterialId(material_of(x, y, z))));
            }
        }
    }
    grid
}

fn on_floor(voxel_size: f64) -> DynamicScene {
    DynamicScene {
        voxel_size,
        ..DynamicScene::default()
    }
}

#[test]
fn stiffness_ratio_1e4_in_one_body() {
    let palette = Palette(vec![material(1e9, false), material(1e5, false)]);
    let grid = block([4, 4, 4], |x, _, _| u8::from(x >= 2));
    run_passive(&grid, &palette, &on_floor(0.01), 0.0);
}

#[test]
fn youngs_modulus_from_1e3_to_1e10_pa() {
    for e in [1e3, 1e6, 1e10] {
        let palette = Palette(vec![material(e, false)]);
        run_passive(
            &block([3, 3, 3], |_, _, _| 0),
            &palette,
            &on_floor(0.01),
            0.0,
        );
    }
}

#[test]
fn voxel_size_from_1e_4_to_1_m() {
    for s in [1e-4, 1e-2, 1.0] {
        let palette = Palette(vec![material(1e6, false)]);
        run_passive(&block([3, 3, 3], |_, _, _| 0), &palette, &on_floor(s), 0.0);
    }
}

#[test]
fn zero_internal_damping_with_poisson_0_35_past_one_second() {
    // The reference engine diverges at about 1 s here; run 1.5 s of simulated time, without and
    // with the lateral Poisson coupling (a 4³ block has interior voxels, so the coupling acts).
    let palette = Palette(vec![material(1e6, false)]);
    for poisson in [false, true] {
        let scene = DynamicScene {
            poisson,
            damping: DampingParams {
                link: 0.0,
                global: 0.0,
                contact: 1.0,
            },
            ..on_floor(0.01)
        };
        let grid = block([4, 4, 4], |_, _, _| 0);
        let sim = Simulation::new(&grid, &palette, &scene).unwrap();
        assert_eq!(sim.passes().contains(&Pass::Poisson), poisson);
        let steps = run_passive(&grid, &palette, &scene, 1.5);
        assert!(steps >= MIN_STEPS);
    }
}

#[test]
fn stiffness_ratio_1e4_with_poisson_coupling() {
    let palette = Palette(vec![material(1e9, false), material(1e5, false)]);
    let grid = block([5, 5, 5], |x, _, _| u8::from(x >= 2));
    let scene = DynamicScene {
        poisson: true,
        ..on_floor(0.01)
    };
    run_passive(&grid, &palette, &scene, 0.0);
}

#[test]
fn single_voxel() {
    let palette = Palette(vec![material(1e6, false)]);
    run_passive(
        &block([1, 1, 1], |_, _, _| 0),
        &palette,
        &on_floor(0.01),
        0.0,
    );
}

#[test]
fn one_voxel_thick_sheet() {
    let palette = Palette(vec![material(1e6, false)]);
    run_passive(
        &block([12, 12, 1], |_, _, _| 0),
        &palette,
        &on_floor(0.01),
        0.0,
    );
}

#[test]
fn slender_chain_of_100_voxels() {
    let palette = Palette(vec![material(1e6, false)]);
    run_passive(
        &block([100, 1, 1], |_, _, _| 0),
        &palette,
        &on_floor(0.01),
        0.0,
    );
}

#[test]
fn actuation_of_50_percent_volume() {
    let palette = Palette(vec![material(1e6, false), material(1e6, true)]);
    let grid = block([4, 4, 4], |x, _, _| u8::from(x < 2));
    let period = 0.05;
    let scene = DynamicScene {
        actuation: Some(Actuation {
            amplitude_volume: 0.5,
            period,
            phase: 0.0,
        }),
        ..on_floor(0.01)
    };
    let mut sim = Simulation::new(&grid, &palette, &scene).unwrap();
    sim.start_actuation();
    // Surface speed of the actuation: body size × linear amplitude × 2π/T.
    let linear_amplitude = 1.5_f64.cbrt() - 1.0;
    let body = 0.04;
    let surface_speed = body * linear_amplitude * 2.0 * std::f64::consts::PI / period;
    // A bounded response: the body's first axial mode, c / 2L with c = √(E/ρ), is near 400 Hz,
    // so the 20 Hz actuation drives it quasi-statically, amplified by 1 / (1 − (f/f₁)²). Starting
    // from rest adds a free vibration of at most that surface speed (the velocity the
    // quasi-static motion starts with), and friction can move the whole body no faster than its
    // surfaces move: three surface speeds, amplified. A diverging integration passes any bound.
    let first_mode = (1e6_f64 / 1000.0).sqrt() / (2.0 * body);
    let amplification = 1.0 / (1.0 - (1.0 / period / first_mode).powi(2));
    let bound = 3.0 * amplification * surface_speed;
    let steps = MIN_STEPS.max((2.0 * period / sim.dt()) as u64);
    for _ in 0..steps {
        sim.step().unwrap_or_else(|d| panic!("diverged: {d}"));
        assert!(
            sim.max_speed() < bound,
            "speed {} above {bound}",
            sim.max_speed()
        );
    }
}
