use super::*;
use crate::dynamics::state::build_state;
use crate::material::{Material, MaterialId, Palette};
use crate::voxel::{GridDims, VoxelGrid};

/// Eleven voxels (two blocks of four and a scalar tail) in a varied state: the dispatched
/// lanes, the portable lanes and the one-voxel formula give the same bits, large spins
/// included, and the summary agrees.
#[test]
fn lanes_and_the_one_voxel_formula_agree_bit_for_bit() {
    let grid = VoxelGrid::filled(GridDims::new(11, 1, 1), MaterialId(0));
    let palette = Palette(vec![Material::new("m", 1.0e6, 0.35)]);
    let (mut v, _) = build_state(&grid, &palette, 0.01, 0.5).unwrap();
    for i in 0..v.len() {
        let t = i as f64;
        let wave = |a: f64, b: f64, c: f64| Vec3::new((a * t).sin(), (b * t).cos(), (c * t).sin());
        v.position[i] += wave(0.7, 1.3, 2.1) * 1e-3;
        let angle = if i % 5 == 2 { 2.5 } else { 0.05 };
        v.orientation[i] = Quat::from_rotation_vector(wave(0.3, 0.5, 0.9) * angle);
        v.momentum[i] = wave(1.1, 0.2, 0.4) * 1e-4;
        v.angular_momentum[i] = wave(0.6, 1.7, 0.8) * 1e-7;
        v.force[i] = wave(0.9, 0.1, 1.9) * 3.0;
        v.torque[i] = wave(0.2, 2.3, 0.5) * 1e-3;
    }
    let dt = 1e-4;
    let (mut a, mut b, mut c) = (v.clone(), v.clone(), v.clone());
    let sa = integrate_pass(&mut a, dt);
    let sb = integrate_lanes(Portable, VoxelState::new(&mut b), dt);
    let mut sc = IntegrationSummary {
        max_speed2: 0.0,
        checksum: 0.0,
    };
    let n = c.len();
    let mut one = VoxelState::new(&mut c);
    for i in 0..n {
        integrate_voxel(&mut one, i, dt, &mut sc);
    }
    let bits = |w: &Voxels| -> Vec<u64> {
        let vec3 = |u: &[Vec3]| -> Vec<u64> {
            u.iter()
                .flat_map(|u| [u.x.to_bits(), u.y.to_bits(), u.z.to_bits()])
                .collect()
        };
        [
            &w.position,
            &w.momentum,
            &w.velocity,
            &w.angular_momentum,
            &w.angular_velocity,
            &w.force,
            &w.torque,
        ]
        .into_iter()
        .flat_map(|u| vec3(u))
        .chain(
            w.orientation
                .iter()
                .flat_map(|q| [q.w, q.x, q.y, q.z].map(f64::to_bits)),
        )
        .collect()
    };
    assert_eq!(bits(&a), bits(&c));
    assert_eq!(bits(&b), bits(&c));
    assert!(a.force.iter().all(|f| *f == Vec3::ZERO));
    assert_ne!(bits(&a), bits(&v), "the step moved nothing");
    for s in [sa, sb] {
        assert_eq!(s.max_speed2.to_bits(), sc.max_speed2.to_bits());
        assert_eq!(s.checksum.to_bits(), 0.0f64.to_bits());
    }
}
