use super::*;

const M: f64 = 1e-3;
const K: f64 = 1e3;
const PEN: f64 = 1e-5;
const DT: f64 = 1e-4;

/// One voxel 10 µm into the floor (elastic normal force K·PEN = 0.01 N, no normal velocity),
/// μs = 1, μk = 0.5, moving at `speed` along +X and pulled along +X by `pull`.
fn one_voxel(speed: f64, pull: f64) -> (Voxels, FloorContact) {
    let voxels = Voxels {
        position: vec![Vec3::new(0.0, 0.0, 0.5e-3 - PEN)],
        velocity: vec![Vec3::new(speed, 0.0, 0.0)],
        momentum: vec![Vec3::new(M * speed, 0.0, 0.0)],
        force: vec![Vec3::new(pull, 0.0, 0.0)],
        mass: vec![M],
        static_friction: vec![1.0],
        kinetic_friction: vec![0.5],
        actuated: vec![false],
        ..Voxels::default()
    };
    let contact = FloorContact {
        stiffness: vec![K],
        damping: vec![0.0],
        sticking: vec![false],
        law: FrictionLaw::Voxcad,
    };
    (voxels, contact)
}

fn run(speed: f64, pull: f64) -> (Vec3, Vec3, bool) {
    let (mut v, mut c) = one_voxel(speed, pull);
    floor_pass(&mut v, &mut c, 0.5e-3, 0.5e-3, DT);
    (v.force[0], v.momentum[0], c.sticking[0])
}

#[test]
fn voxcad_friction_holds_a_stopped_voxel_only_below_the_static_limit() {
    // Normal force 0.01 N: static limit 0.01 N, kinetic 0.005 N.
    let (f, p, stuck) = run(0.0, 0.009);
    assert!(stuck && f.x == 0.0 && p.x == 0.0);
    // Pulled past the limit, a stopped voxel gets no friction in that step.
    let (f, _, stuck) = run(0.0, 0.011);
    assert!(!stuck);
    assert_eq!(f.x, 0.011);
    assert!(
        (f.z / (K * PEN) - 1.0).abs() < 1e-9,
        "the elastic normal force: {f:?}"
    );
}

#[test]
fn voxcad_friction_slows_a_slider_and_stops_it_whatever_pulls_it() {
    // Friction removes μk·N·dt = 5e-7 N·s a step; 1 mm/s of a gram is 1e-6: it slides on.
    let (f, _, stuck) = run(1e-3, 0.02);
    assert!(!stuck);
    assert!((f.x - (0.02 - 0.005)).abs() < 1e-15, "{f:?}");
    // At 0.4 mm/s (4e-7 N·s) friction would stop it within the step: it is stopped, even
    // pulled at twice the static limit.
    let (f, p, stuck) = run(4e-4, 0.02);
    assert!(stuck && f.x == 0.0 && p.x == 0.0);
}
