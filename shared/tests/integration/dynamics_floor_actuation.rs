//! Floor friction against the incline solution, volumetric actuation against its prescribed
//! volume, and divergence as a typed outcome.

use amorph::dynamics::{
    Actuation, DampingParams, DivergenceReason, DynamicScene, Floor, FrictionLaw, Simulation,
    foam_palette,
};
use amorph::material::{Material, MaterialId, Palette};
use amorph::task::locomotion::{LocomotionProtocol, LocomotionStatus, simulate_locomotion};
use amorph::voxel::{GridDims, VoxelGrid};

const G: f64 = 9.81;

/// Both friction laws must give the incline's answers: they differ only in when a voxel switches
/// between sticking and sliding, not in what sticking and sliding are.
const LAWS: [FrictionLaw; 2] = [FrictionLaw::Sticking, FrictionLaw::Voxcad];

fn block_on_incline(incline_deg: f64, friction: FrictionLaw) -> Simulation {
    // μs = 1.0 (friction angle 45°), μk = 0.3.
    let mut rubber = Material::new("rubber", 1.0e6, 0.35);
    rubber.static_friction = 1.0;
    rubber.kinetic_friction = 0.3;
    let grid = VoxelGrid::filled(GridDims::new(2, 2, 2), MaterialId(0));
    let scene = DynamicScene {
        voxel_size: 0.01,
        floor: Some(Floor {
            incline: incline_deg.to_radians(),
            friction,
            ..Floor::default()
        }),
        ..DynamicScene::default()
    };
    Simulation::new(&grid, &Palette(vec![rubber]), &scene).unwrap()
}

#[test]
fn block_holds_below_the_friction_angle() {
    // A tilt-table measurement: the block is set down on the level floor, and the floor is then
    // raised to 40° slowly compared with the block's vibration (~ms). Starting on the incline
    // instead would drop the block onto it: for the first ~1 ms its contact force is still
    // building, below what static friction needs against g sin θ, so it slips, and kinetic
    // friction (μk = 0.3 < tan 40°) can never stop it again: a dropped block really slides.
    for law in LAWS {
        let mut sim = block_on_incline(0.0, law);
        sim.run_for(0.05).unwrap();
        let x0 = sim.centre_of_mass().x;
        let (ramp, target) = (0.1, 40.0_f64.to_radians());
        let steps = (ramp / sim.dt()).ceil() as u64;
        for k in 1..=steps {
            sim.set_incline(target * k as f64 / steps as f64).unwrap();
            sim.step().unwrap();
        }
        sim.run_for(0.3).unwrap();
        let slid = sim.centre_of_mass().x - x0;
        eprintln!("{law:?}: slid {slid:.3e} m");
        // Sticking voxels do not move tangentially at all; only the elastic shear of the block under
        // its own weight remains, ρ g h²/G ~ 1e-6 m. Sliding for 0.3 s would cover ~0.1 m.
        assert!(slid.abs() < 1e-5, "{law:?}: slid {slid} m");
    }
}

#[test]
fn block_slides_above_the_friction_angle_with_the_kinetic_acceleration() {
    let theta: f64 = 50.0_f64.to_radians();
    for law in LAWS {
        let mut sim = block_on_incline(50.0, law);
        // Let the contact transient die out (a few contact periods, ~1 ms), then measure.
        sim.run_for(0.02).unwrap();
        let (t1, v1) = (sim.time(), sim.linear_momentum().x);
        sim.run_for(0.2).unwrap();
        let (t2, v2) = (sim.time(), sim.linear_momentum().x);
        let mass = 8.0 * 1000.0 * 1e-6;
        let measured = (v2 - v1) / mass / (t2 - t1);
        let analytic = G * (theta.sin() - 0.3 * theta.cos());
        let error = measured / analytic - 1.0;
        eprintln!(
            "{law:?}: incline acceleration {measured:.4} m/s², analytic {analytic:.4}, error {:.3} %",
            100.0 * error
        );
        // Σ μk·N_i = μk·m g cos θ exactly once the normal forces are steady; the 2 % bound
        // covers the residual contact ringing.
        assert!(error.abs() < 0.02, "{law:?}: error {error}");
    }
}

fn volume_ratio(sim: &Simulation, initial: [f64; 3]) -> f64 {
    let extent = extents(sim);
    (0..3).map(|k| extent[k] / initial[k]).product()
}

fn extents(sim: &Simulation) -> [f64; 3] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in sim.positions() {
        for (k, c) in [p.x, p.y, p.z].into_iter().enumerate() {
            lo[k] = lo[k].min(c);
            hi[k] = hi[k].max(c);
        }
    }
    [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
}

#[test]
fn free_actuated_cube_breathes_20_percent_in_volume_within_1_percent() {
    let mut m = Material::new("actuated", 1.0e6, 0.35);
    m.actuated = true;
    let grid = VoxelGrid::filled(GridDims::new(4, 4, 4), MaterialId(0));
    let scene = DynamicScene {
        // The cube's lowest mode is ~4 ms; a 0.1 s period keeps the response quasi-static
        // (dynamic amplification ~(0.004/0.1)² < 0.2 %).
        actuation: Some(Actuation {
            amplitude_volume: 0.2,
            period: 0.1,
            phase: 0.0,
        }),
        damping: DampingParams {
            link: 1.0,
            global: 0.0,
            contact: 0.0,
        },
        ..DynamicScene::free_space(0.01)
    };
    let mut sim = Simulation::new(&grid, &Palette(vec![m]), &scene).unwrap();
    let initial = extents(&sim);
    sim.start_actuation();
    sim.run_for(0.1).unwrap(); // first cycle: start-up transient
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let steps = (0.1 / sim.dt()) as u64;
    for _ in 0..steps {
        sim.step().unwrap();
        let v = volume_ratio(&sim, initial);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    eprintln!("volume ratio between {lo:.5} and {hi:.5}");
    // Uniform expansion of every link by λ = (1 + a sin)^⅓ gives the volume 1 ± 0.2 exactly in the
    // quasi-static limit; the bound is 1 % of the target.
    assert!((hi - 1.2).abs() < 0.012, "max volume {hi}");
    assert!((lo - 0.8).abs() < 0.008, "min volume {lo}");
}

#[test]
fn divergence_is_an_outcome_with_reason_and_time() {
    let grid = VoxelGrid::filled(GridDims::new(4, 4, 4), MaterialId(1));
    let scene = DynamicScene {
        dt_fraction: 20.0, // far beyond the stable step
        ..DynamicScene::paper_locomotion()
    };
    let outcome = simulate_locomotion(
        &grid,
        &foam_palette(),
        &scene,
        &LocomotionProtocol::default(),
    );
    match &outcome.status {
        LocomotionStatus::Diverged { reason, time } => {
            assert!(time.is_finite() && *time > 0.0);
            // The reason carries the figure that crossed its limit: it must be over it (or the
            // state non-finite), else the check fired on a healthy state.
            let limits = &scene.divergence;
            match reason {
                DivergenceReason::Strain { strain, limit } => {
                    assert_eq!(*limit, limits.max_strain);
                    assert!(strain > limit, "{strain} <= {limit}");
                }
                DivergenceReason::Runaway { travel, limit } => {
                    assert_eq!(*limit, limits.max_step_travel);
                    assert!(travel > limit, "{travel} <= {limit}");
                }
                DivergenceReason::NonFinite => {}
            }
        }
        other => panic!("expected divergence, got {other:?}"),
    }
    // Detected within a few steps of blowing up, never as a NaN fitness.
    assert!(outcome.steps < 1000, "took {} steps", outcome.steps);
    assert_eq!(outcome.fitness, 0.0);
}

#[test]
fn empty_design_is_an_outcome() {
    let grid = VoxelGrid::empty(GridDims::new(3, 3, 3));
    let outcome = simulate_locomotion(
        &grid,
        &foam_palette(),
        &DynamicScene::paper_locomotion(),
        &LocomotionProtocol::default(),
    );
    assert_eq!(outcome.status, LocomotionStatus::Empty);
}

#[test]
fn a_diverged_simulation_stays_as_it_was_found() {
    // After a divergence every further step returns the same divergence and leaves the state,
    // time and step count alone, so a caller that keeps stepping learns nothing new and changes
    // nothing.
    let grid = VoxelGrid::filled(GridDims::new(3, 3, 3), MaterialId(1));
    let scene = DynamicScene {
        dt_fraction: 20.0,
        ..DynamicScene::paper_locomotion()
    };
    let mut sim = Simulation::new(&grid, &foam_palette(), &scene).unwrap();
    let first = loop {
        if let Err(d) = sim.step() {
            break d;
        }
        assert!(sim.steps() < 10_000, "did not diverge");
    };
    let (time, steps) = (sim.time(), sim.steps());
    let positions = sim.positions().to_vec();
    for _ in 0..5 {
        assert_eq!(sim.step(), Err(first.clone()));
    }
    assert_eq!(sim.run_steps(100), Err(first.clone()));
    assert_eq!((sim.time(), sim.steps()), (time, steps));
    assert_eq!(sim.positions(), &positions[..]);
}

/// One actuated voxel resting on the floor, actuated slowly (1 s against a contact period of
/// ~2 ms, critically damped): its centre sits where the floor spring carries its weight, z = r − mg/k,
/// r being how far the floor reaches the centre. With `actuated_contact` r is half the swelling
/// size, s/2·λ(t), so the centre rises and falls with the swelling; without it r stays s/2.
fn lone_voxel_heights(actuated_contact: bool) -> Vec<(f64, f64)> {
    let mut m = Material::new("actuated", 1.0e6, 0.35);
    m.actuated = true;
    let grid = VoxelGrid::filled(GridDims::new(1, 1, 1), MaterialId(0));
    let scene = DynamicScene {
        voxel_size: 0.01,
        floor: Some(Floor {
            actuated_contact,
            ..Floor::default()
        }),
        actuation: Some(Actuation {
            amplitude_volume: 0.2,
            period: 1.0,
            phase: 0.0,
        }),
        damping: DampingParams {
            link: 1.0,
            global: 0.0,
            contact: 1.0,
        },
        ..DynamicScene::default()
    };
    let mut sim = Simulation::new(&grid, &Palette(vec![m]), &scene).unwrap();
    sim.run_for(0.05).unwrap(); // settle onto the floor
    sim.start_actuation();
    sim.run_for(0.25).unwrap(); // start-up transient
    let mut samples = Vec::new();
    let steps = (1.0 / sim.dt()) as u64;
    for i in 0..steps {
        sim.step().unwrap();
        if i % 50 == 0 {
            samples.push((sim.actuation_factor(), sim.positions()[0].z));
        }
    }
    samples
}

#[test]
fn an_actuated_voxel_meets_the_floor_at_its_actuated_size_when_asked() {
    let (s, k, mg) = (
        0.01,
        1.0e6 * 0.01,
        Material::new("m", 1.0e6, 0.35).density * 1e-6 * G,
    );
    // The swing of the centre the swelling alone would give: s/2·(λmax − λmin) ≈ 0.32 mm.
    let swing = 0.5 * s * (1.2f64.cbrt() - 0.8f64.cbrt());
    // Quasi-static tracking error of a critically damped contact at 1/500 of its frequency:
    // a phase lag of 2ζω/ωn ≈ 0.004 rad of the swing (~1.3 µm); 2 % of the swing bounds it.
    let tolerance = 0.02 * swing;
    for (lambda, z) in lone_voxel_heights(true) {
        let expected = 0.5 * s * lambda - mg / k;
        assert!(
            (z - expected).abs() < tolerance,
            "at λ = {lambda:.4} the centre is at {z:.6e} m, the floor spring puts it at {expected:.6e} m"
        );
    }
    let rest: Vec<f64> = lone_voxel_heights(false).iter().map(|&(_, z)| z).collect();
    for z in &rest {
        assert!((z - (0.5 * s - mg / k)).abs() < tolerance, "{z:.6e}");
    }
}
