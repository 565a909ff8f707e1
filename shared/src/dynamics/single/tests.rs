//! The mixed-precision kernel: its dispatched and portable forms alike to the bit, the f64
//! kernel's loads, translation invariance.

use super::*;
use crate::dynamics::link::tests::vary;
use crate::dynamics::link::{link_pass, link_pass_lanes, scatter_into};
use crate::dynamics::single_lanes::Single;
use crate::dynamics::state::build_state;
use crate::material::{Material, MaterialId, Palette};
use crate::voxel::{GridDims, VoxelGrid};

/// A 9×3×2 block of 10 mm voxels (runs of eight x-links, groups that are not runs, a
/// partial last group and a voxel count that is not a multiple of four) in the varied state
/// of the double kernel's tests, everything moved by `shift`.
fn state(shift: Vec3) -> (Voxels, Links) {
    let grid = VoxelGrid::filled(GridDims::new(9, 3, 2), MaterialId(0));
    let palette = Palette(vec![Material::new("m", 1.0e6, 0.35)]);
    let (mut v, links) = build_state(&grid, &palette, 0.01, 0.5).unwrap();
    assert_ne!(links.len() % SINGLE_LANES, 0);
    assert_ne!(v.len() % LANES, 0);
    vary(&mut v, shift);
    (v, links)
}

const STEP: LinkStep = LinkStep {
    voxel_size: 0.01,
    actuation_factor: 1.05,
};

/// The mixed pass on portable lanes, the copy written on portable lanes too; `RUNS` false
/// reads every group through the general gather.
fn portable<const RUNS: bool>(links: &Links, v: &mut Voxels) -> f64 {
    let mut single = SingleCopy::new(links, v.len());
    copy_lanes::<_, true>(
        Portable,
        CopyJob {
            voxels: v,
            state: &mut single.state,
        },
    );
    let (_, out) = scatter_into(v);
    let job = single.job(links, 0..links.len(), STEP, out);
    link_pass_lanes::<_, _, _, SINGLE_LANES, true, true, RUNS>(Single(Portable), job)
}

fn mixed(links: &Links, v: &mut Voxels) -> f64 {
    let mut single = SingleCopy::new(links, v.len());
    single.copy_state::<true>(v);
    crate::dynamics::link::link_pass_mixed::<true, true>(links, &single, v, STEP)
}

fn bits(w: &[Vec3]) -> Vec<[u64; 3]> {
    w.iter()
        .map(|u| [u.x.to_bits(), u.y.to_bits(), u.z.to_bits()])
        .collect()
}

/// The largest difference between two voxels' sums, relative to the largest sum.
fn relative_difference(a: &[Vec3], b: &[Vec3]) -> f64 {
    let largest = a.iter().map(|u| u.norm()).fold(0.0, f64::max);
    let worst = a
        .iter()
        .zip(b)
        .map(|(u, w)| (*u - *w).norm())
        .fold(0.0, f64::max);
    worst / largest
}

/// The dispatched mixed pass (AVX2 where the CPU has it), the portable one, and the portable
/// one reading every group through the general gather give the same bits.
#[test]
fn dispatched_and_portable_single_kernels_agree_bit_for_bit() {
    let (v, links) = state(Vec3::ZERO);
    let (mut a, mut b, mut c) = (v.clone(), v.clone(), v.clone());
    let strain_a = mixed(&links, &mut a);
    let strain_b = portable::<true>(&links, &mut b);
    let strain_c = portable::<false>(&links, &mut c);
    assert_eq!(strain_a.to_bits(), strain_b.to_bits());
    assert_eq!(strain_a.to_bits(), strain_c.to_bits());
    for (x, y) in [(&a, &b), (&a, &c)] {
        assert_eq!(bits(&x.force), bits(&y.force));
        assert_eq!(bits(&x.torque), bits(&y.torque));
    }
    assert_ne!(bits(&a.torque), bits(&v.torque), "the pass added nothing");
}

/// The mixed pass computes the double pass's forces and moments to `f32` accuracy. The
/// tolerance, 1e-4 of the largest sum: rounding positions of up to 9 cm to `f32` (7.5e-9 m)
/// is 7.5e-6 of the ~1 mm deformations of this state, and each of the kernel's few dozen
/// dependent `f32` operations adds about 6e-8; a lane mix-up or a dropped term is an error of
/// order one.
#[test]
fn the_mixed_kernel_computes_the_double_kernels_loads() {
    let (v, links) = state(Vec3::ZERO);
    let (mut double, mut single) = (v.clone(), v.clone());
    let strain_double = link_pass::<true, true>(&links, &mut double, STEP);
    let strain_single = mixed(&links, &mut single);
    assert!((strain_single - strain_double).abs() <= 1e-4 * strain_double);
    let loads = |w: &Voxels, c: fn(&Voxels) -> &Vec<Vec3>| -> Vec<Vec3> {
        c(w).iter().zip(c(&v)).map(|(u, u0)| *u - *u0).collect()
    };
    for (name, c) in [
        (
            "force",
            (|w: &Voxels| &w.force) as fn(&Voxels) -> &Vec<Vec3>,
        ),
        ("torque", |w: &Voxels| &w.torque),
    ] {
        let e = relative_difference(&loads(&double, c), &loads(&single, c));
        assert!(e < 1e-4, "{name}: relative difference {e:e}");
    }
}

/// The copy holds positions relative to voxel 0, so a body 1 m from the origin gets the loads
/// it gets at the origin (to the `f64` rounding of the shifted positions, ~1e-16 m, which
/// `f32` rounds away almost everywhere). Rounding absolute positions instead would be off by
/// the `f32` spacing at 1 m, 6e-8 m, 6e-5 of the deformations: 60 times this tolerance.
#[test]
fn the_mixed_kernel_is_translation_invariant() {
    let (here, links) = state(Vec3::ZERO);
    let (there, _) = state(Vec3::new(1.0, -0.75, 0.5));
    let (mut a, mut b) = (here.clone(), there.clone());
    mixed(&links, &mut a);
    mixed(&links, &mut b);
    for (w, w0, name) in [
        (&a.force, &here.force, "force"),
        (&b.force, &there.force, "force, shifted"),
    ] {
        assert_ne!(bits(w), bits(w0), "{name}: the pass added nothing");
    }
    let less = |w: &[Vec3], w0: &[Vec3]| -> Vec<Vec3> {
        w.iter().zip(w0).map(|(u, u0)| *u - *u0).collect()
    };
    let e = relative_difference(&less(&a.force, &here.force), &less(&b.force, &there.force));
    assert!(e < 1e-6, "relative difference {e:e}");
}
