use super::super::math::Quat;
use super::super::state::TOP_EIGENVALUE;
use super::*;
use crate::material::{Material, MaterialId};
use crate::voxel::GridDims;

/// Largest eigenvalue of M⁻¹K (translations and rotations) of an n-block at rest, in units
/// of (EA/L)/m, by power iteration on the link pass around the rest state.
fn top_eigenvalue(n: [usize; 3]) -> f64 {
    let grid = VoxelGrid::filled(GridDims::new(n[0], n[1], n[2]), MaterialId(0));
    let palette = Palette(vec![Material::new("rubber", 1e6, 0.35)]);
    let s = 0.01;
    let (mut v, links) = build_state(&grid, &palette, s, 0.0).unwrap();
    let rest = v.position.clone();
    let count = v.len();
    // A deterministic start vector with a component along every direction.
    let mut u: Vec<f64> = (0..6 * count)
        .map(|i| ((i * 7919) % 13) as f64 - 6.0)
        .collect();
    let eps = 1e-9;
    let mut lambda = 0.0;
    for _ in 0..300 {
        let norm = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        u.iter_mut().for_each(|x| *x /= norm);
        for i in 0..count {
            let (sm, si) = (v.mass[i].sqrt(), (v.mass[i] * s * s / 6.0).sqrt());
            let t = Vec3::new(u[6 * i], u[6 * i + 1], u[6 * i + 2]);
            let r = Vec3::new(u[6 * i + 3], u[6 * i + 4], u[6 * i + 5]);
            v.position[i] = rest[i] + t * (eps / sm);
            v.orientation[i] = Quat::from_rotation_vector(r * (eps / si));
            v.force[i] = Vec3::ZERO;
            v.torque[i] = Vec3::ZERO;
        }
        let step = LinkStep {
            voxel_size: s,
            actuation_factor: 1.0,
        };
        link_pass::<false, false>(&links, &mut v, step);
        let mut w = vec![0.0; 6 * count];
        for i in 0..count {
            let (sm, si) = (v.mass[i].sqrt(), (v.mass[i] * s * s / 6.0).sqrt());
            let f = v.force[i] * (-1.0 / (eps * sm));
            let t = v.torque[i] * (-1.0 / (eps * si));
            w[6 * i..6 * i + 6].copy_from_slice(&[f.x, f.y, f.z, t.x, t.y, t.z]);
        }
        lambda = w.iter().zip(&u).map(|(a, b)| a * b).sum::<f64>();
        u = w;
    }
    lambda / (1e6 * s / (1000.0 * s * s * s))
}

#[test]
fn damping_reference_bounds_the_lattice_spectrum() {
    // The stiffness-proportional link damping gives the top mode ζ·√(λ/TOP_EIGENVALUE); it
    // must not exceed ζ (stability of the explicit step), nor fall far below it.
    for (n, expected) in [([2, 1, 1], 5.0), ([6, 6, 6], 13.1), ([12, 12, 1], 11.9)] {
        let lambda = top_eigenvalue(n);
        assert!(lambda < TOP_EIGENVALUE, "{n:?}: {lambda}");
        assert!((lambda - expected).abs() < 0.1, "{n:?}: {lambda}");
    }
}
