use super::*;
use crate::dynamics::math::Vec3;
use crate::dynamics::state::build_state;
use crate::material::{Material, MaterialId, Palette};
use crate::voxel::{GridDims, VoxelGrid};

/// The pass against the formula written out link by link in link order (each link's length
/// measured once in the pass, twice here), on a deformed 5×4×3 block with two materials and
/// actuated links: the same bits.
#[test]
fn the_pass_and_the_link_by_link_formula_agree_bit_for_bit() {
    let mut grid = VoxelGrid::filled(GridDims::new(5, 4, 3), MaterialId(0));
    grid.set(2, 1, 1, Some(MaterialId(1)));
    grid.set(4, 3, 2, Some(MaterialId(1)));
    let mut soft = Material::new("soft", 2.0e5, 0.45);
    soft.actuated = true;
    let palette = Palette(vec![Material::new("hard", 1.0e6, 0.35), soft]);
    let s = 0.01;
    let (mut v, mut links) = build_state(&grid, &palette, s, 0.5).unwrap();
    for i in 0..v.len() {
        let t = i as f64;
        v.position[i] += Vec3::new((0.7 * t).sin(), (1.3 * t).cos(), (2.1 * t).sin()) * 1e-4;
        // Forces already there (the link pass's), so that the order of the sums shows.
        v.force[i] = Vec3::new((0.3 * t).cos(), (1.1 * t).sin(), (0.4 * t).cos()) * 1e-2;
    }
    let mut coupling = PoissonCoupling::apply_to_links(&v, &mut links, s);
    assert!(coupling.is_active());
    let step = LinkStep {
        voxel_size: s,
        actuation_factor: 1.03,
    };
    let stretch = step.actuation_factor - 1.0;
    let mut expected = v.clone();
    let c = &coupling;
    let mut strain = vec![[0.0; 3]; v.len()];
    for k in 0..links.len() {
        let (a, b, axis) = (
            links.a[k] as usize,
            links.b[k] as usize,
            links.axis[k] as usize,
        );
        let e = ((v.position[b] - v.position[a]).norm() / links.rest_length(k, s, stretch) - 1.0)
            * c.root_modulus[k];
        strain[a][axis] += e * c.scale[a][axis];
        strain[b][axis] += e * c.scale[b][axis];
    }
    for (e, scale) in strain.iter_mut().zip(&c.scale) {
        let [ex, ey, ez] = *e;
        *e = [
            c.volume * (ey + ez) * scale[0],
            c.volume * (ex + ez) * scale[1],
            c.volume * (ex + ey) * scale[2],
        ];
    }
    for k in 0..links.len() {
        let (a, b, axis) = (
            links.a[k] as usize,
            links.b[k] as usize,
            links.axis[k] as usize,
        );
        let g = (strain[a][axis] + strain[b][axis]) * c.root_modulus[k];
        let r = v.position[b] - v.position[a];
        let f = r * (g / (r.norm() * links.rest_length(k, s, stretch)));
        expected.force[a] += f;
        expected.force[b] -= f;
    }
    let bits = |w: &Voxels| -> Vec<u64> {
        w.force
            .iter()
            .flat_map(|f| [f.x, f.y, f.z].map(f64::to_bits))
            .collect()
    };
    let mut computed = v.clone();
    coupling.pass(&links, &mut computed, step);
    assert_eq!(bits(&computed), bits(&expected));
    assert!(expected.force.iter().any(|f| f.norm() > 0.0));
}

/// Under uniaxial stress the condensed constants give back Young's modulus E and the lateral
/// strain −ν ε, in 3-D (σ₂ = σ₃ = 0) and in plane stress (σ₂ = 0).
#[test]
fn condensed_constants_give_young_and_poisson_under_uniaxial_stress() {
    let (e, nu) = (3.0e5, 0.35);
    let (m, l) = condensed(e, nu, 3);
    // ε₂ = ε₃ = −ν ε₁ makes σ₂ = l ε₁ + (m + l) ε₂ vanish, and σ₁ = m ε₁ + 2 l ε₂ = E ε₁.
    assert!((l + (m + l) * -nu).abs() < 1e-9 * e);
    assert!((m - 2.0 * l * nu - e).abs() < 1e-9 * e);
    let (m, l) = condensed(e, nu, 2);
    assert!((l + m * -nu).abs() < 1e-9 * e);
    assert!((m - l * nu - e).abs() < 1e-9 * e);
    assert_eq!(condensed(e, nu, 1), (e, 0.0));
}
