use super::*;
use crate::dynamics::math::Vec3;
use crate::dynamics::state::build_state;
use crate::material::{Material, MaterialId, Palette};
use crate::voxel::{GridDims, VoxelGrid};

/// A varied state for the kernels' tests: positions moved by up to 1 mm (and by `shift`),
/// small rotations and, on every seventh voxel, 2.5 rad ones (the `atan2` lanes), velocities,
/// spins, and forces and torques already summed, so that the order in which links add to a
/// voxel shows.
pub(in crate::dynamics) fn vary(v: &mut Voxels, shift: Vec3) {
    for i in 0..v.len() {
        let t = i as f64;
        let wave = |a: f64, b: f64, c: f64| Vec3::new((a * t).sin(), (b * t).cos(), (c * t).sin());
        v.position[i] += wave(0.7, 1.3, 2.1) * 1e-3 + shift;
        let angle = if i % 7 == 3 { 2.5 } else { 0.05 };
        v.orientation[i] = Quat::from_rotation_vector(wave(0.3, 0.5, 0.9) * angle);
        v.velocity[i] = wave(1.1, 0.2, 0.4) * 0.1;
        v.angular_velocity[i] = wave(0.6, 1.7, 0.8) * 3.0;
        v.force[i] = wave(0.2, 0.9, 1.4) * 10.0;
        v.torque[i] = wave(1.6, 0.3, 0.7) * 0.1;
    }
}

/// The dispatched pass (explicit AVX2 vectors where the CPU has them) and the portable lane
/// kernel give the same bits, large rotations (the `atan2` lanes) and a partial last group
/// included; and so do runs read as blocks and the same links read one by one.
#[test]
fn dispatched_and_baseline_kernels_agree_bit_for_bit() {
    let grid = VoxelGrid::filled(GridDims::new(5, 3, 2), MaterialId(0));
    let palette = Palette(vec![Material::new("m", 1.0e6, 0.35)]);
    let (mut v, links) = build_state(&grid, &palette, 0.01, 0.5).unwrap();
    assert_ne!(links.len() % LANES, 0);
    let runs = (0..links.len() / LANES)
        .filter(|g| {
            let k0 = g * LANES;
            (1..LANES).all(|j| {
                links.a[k0 + j] == links.a[k0] + j as u32
                    && links.b[k0 + j] == links.b[k0] + j as u32
            })
        })
        .count();
    assert!(
        runs > 0 && runs < links.len() / LANES,
        "runs and other groups both"
    );
    vary(&mut v, Vec3::ZERO);
    let step = LinkStep {
        voxel_size: 0.01,
        actuation_factor: 1.05,
    };
    let (mut a, mut b) = (v.clone(), v.clone());
    let strain_a = link_pass::<true, true>(&links, &mut a, step);
    let portable = |voxels: &mut Voxels, runs: bool| {
        let (view, out) = scatter_into(voxels);
        let job = Job::double(&links, view, 0..links.len(), step, out);
        if runs {
            link_pass_lanes::<_, _, _, LANES, true, true, true>(Portable, job)
        } else {
            link_pass_lanes::<_, _, _, LANES, true, true, false>(Portable, job)
        }
    };
    let strain_b = portable(&mut b, true);
    assert_eq!(strain_a.to_bits(), strain_b.to_bits());
    // Runs (four voxels linked to four, read as blocks) against the general gather.
    let mut c = v.clone();
    let strain_c = portable(&mut c, false);
    assert_eq!(strain_a.to_bits(), strain_c.to_bits());
    let bits = |w: &[Vec3]| -> Vec<[u64; 3]> {
        w.iter()
            .map(|u| [u.x.to_bits(), u.y.to_bits(), u.z.to_bits()])
            .collect()
    };
    assert_eq!(bits(&a.force), bits(&b.force));
    assert_eq!(bits(&a.torque), bits(&b.torque));
    assert_eq!(bits(&a.force), bits(&c.force));
    assert_eq!(bits(&a.torque), bits(&c.torque));
    assert!(
        a.torque
            .iter()
            .all(|t| t.norm() > 0.0 && t.norm().is_finite())
    );
}
