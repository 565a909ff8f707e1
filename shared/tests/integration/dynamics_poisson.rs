//! Lateral Poisson coupling (`DynamicScene::poisson`): a bar pulled along its length has Young's
//! modulus E and contracts laterally by ν (up to a surface effect); without the coupling it does
//! not contract; a thin body does not lock; undamped, the coupled lattice conserves energy (the
//! coupling is an exact potential).

use amorph::dynamics::{DampingParams, DynamicScene, Simulation, Vec3};
use amorph::material::{Material, MaterialId, Palette};
use amorph::voxel::{GridDims, VoxelGrid};

const S: f64 = 0.01;
const E: f64 = 1.0e6;
const NU: f64 = 0.35;
const LAYERS: usize = 14;

/// An n×n×14 bar in free space, pulled apart by ±F spread over its end layers (1,250 Pa),
/// damped to rest.
/// Returns (axial strain, lateral strain) measured between the centre layers 4 and 9, and the
/// axial stress F/A.
fn pulled_bar(poisson: bool, n: usize) -> Bar {
    let grid = VoxelGrid::filled(GridDims::new(n, n, LAYERS), MaterialId(0));
    let palette = Palette(vec![Material::new("rubber", E, NU)]);
    let scene = DynamicScene {
        poisson,
        damping: DampingParams {
            link: 1.0,
            global: 0.02,
            contact: 0.0,
        },
        ..DynamicScene::free_space(S)
    };
    let mut sim = Simulation::new(&grid, &palette, &scene).unwrap();
    // 1,250 Pa on the section: a strain of ~1.3e-3.
    let force = 1250.0 * (n as f64 * S).powi(2);
    for x in 0..n {
        for y in 0..n {
            let f = Vec3::new(0.0, 0.0, force / (n * n) as f64);
            let bottom = sim.voxel_at([x, y, 0]).unwrap();
            let top = sim.voxel_at([x, y, LAYERS - 1]).unwrap();
            sim.add_external_force(bottom, f * -1.0).unwrap();
            sim.add_external_force(top, f).unwrap();
        }
    }
    sim.run_for(0.3).unwrap();
    assert!(sim.max_speed() < 1e-5, "not at rest: {}", sim.max_speed());
    let x = sim.positions();
    let layer_z = |z: usize| {
        (0..n * n)
            .map(|i| x[sim.voxel_at([i % n, i / n, z]).unwrap()].z)
            .sum::<f64>()
            / (n * n) as f64
    };
    // Width along x at layer z between columns `first` and n − 1 − `first`, mean over the rows
    // y in first..n − first.
    let width = |z: usize, first: usize| {
        let rows = first..n - first;
        let count = rows.len() as f64;
        rows.map(|y| {
            x[sim.voxel_at([n - 1 - first, y, z]).unwrap()].x
                - x[sim.voxel_at([first, y, z]).unwrap()].x
        })
        .sum::<f64>()
            / count
    };
    let (lo, hi) = (4, 9);
    let axial = (layer_z(hi) - layer_z(lo)) / ((hi - lo) as f64 * S) - 1.0;
    let lateral = |first: usize| {
        (0.5 * (width(lo, first) + width(hi, first))) / ((n - 1 - 2 * first) as f64 * S) - 1.0
    };
    Bar {
        axial,
        lateral: lateral(0),
        inner_lateral: lateral(1),
        stress: force / (n as f64 * S).powi(2),
    }
}

/// Strains measured at the middle of a pulled bar, and the axial stress (Pa).
struct Bar {
    axial: f64,
    /// Lateral strain across the whole width.
    lateral: f64,
    /// Lateral strain between the second and the second-to-last columns (interior links only).
    inner_lateral: f64,
    stress: f64,
}

#[test]
fn a_pulled_bar_has_youngs_modulus_and_contracts_by_poissons_ratio() {
    // Away from its loaded ends the bar is in uniaxial stress. Its interior voxels have the full
    // 3-D constants; its outer columns are condensed to plane stress (a free surface, see
    // `poisson.rs`) and contract less, while the interior, held back by them, contracts a little
    // more. What follows from that without a fit:
    // - across the interior the lateral strain is at least ν times the axial one;
    // - a link touching the surface contracts less than ν but never stretches, so across the
    //   whole width (n rows of n − 1 links, of which the n − 2 inner rows' n − 3 inner links
    //   contract by at least ν) the ratio lies between ν (n − 2)(n − 3)/(n (n − 1)) and ν;
    // - a bar held back laterally is stiffer, but no stiffer than one held fully (uniaxial
    //   strain, the P-wave modulus M = E (1 − ν)/((1 + ν)(1 − 2ν))), so E ≤ modulus ≤ M;
    // - being a surface effect, each departure shrinks as the bar widens.
    // The settle leaves the measured strains a relative error far below 1e-3 (rest to 1e-5 m/s).
    let slack = 1e-3;
    let p_wave = E * (1.0 - NU) / ((1.0 + NU) * (1.0 - 2.0 * NU));
    let mut previous = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for n in [4, 6, 8, 12] {
        let bar = pulled_bar(true, n);
        let (modulus, ratio) = (bar.stress / bar.axial, -bar.lateral / bar.axial);
        let inner = -bar.inner_lateral / bar.axial;
        eprintln!(
            "coupled, {n} wide: E {modulus:.4e} ({:+.2} %), ν {ratio:.4} ({:+.2} %), interior ν {inner:.4} ({:+.2} %)",
            100.0 * (modulus / E - 1.0),
            100.0 * (ratio / NU - 1.0),
            100.0 * (inner / NU - 1.0)
        );
        assert!(
            modulus >= E * (1.0 - slack) && modulus <= p_wave,
            "E {modulus} outside [{E}, {p_wave}]"
        );
        let surface_floor = NU * ((n - 2) * (n - 3)) as f64 / (n * (n - 1)) as f64;
        assert!(
            ratio > surface_floor && ratio < NU,
            "ν {ratio} outside ({surface_floor}, {NU})"
        );
        assert!(inner > NU * (1.0 - slack), "interior ν {inner} below {NU}");
        let departures = (modulus / E - 1.0, 1.0 - ratio / NU, inner / NU - 1.0);
        assert!(
            departures.0 < previous.0 && departures.1 < previous.1 && departures.2 < previous.2,
            "the surface effect must shrink with the width: {departures:?} after {previous:?}"
        );
        previous = departures;
    }
    let bar = pulled_bar(false, 4);
    let (modulus, ratio) = (bar.stress / bar.axial, -bar.lateral / bar.axial);
    eprintln!("uncoupled: E {modulus:.4e}, ν {ratio:.4}");
    assert!((modulus / E - 1.0).abs() < 0.02);
    assert!(ratio.abs() < 0.005, "an uncoupled lattice has ν ≈ 0");
}

#[test]
fn the_coupled_lattice_conserves_energy_undamped() {
    // Measured: 0.64 % without the coupling and 0.39 % with it (the symplectic step's bounded
    // oscillation of the measured energy); a non-conservative coupling would grow without bound.
    for poisson in [false, true] {
        let worst = drift(poisson);
        eprintln!("poisson {poisson}: largest energy deviation over 2e4 steps {worst:.3e}");
        assert!(worst < 0.01, "poisson {poisson}: drift {worst}");
    }
}

fn drift(poisson: bool) -> f64 {
    // A 3×4×5 block, every link undamped, set swinging in shear (velocity growing with height):
    // total energy (kinetic, link and coupling) may only wander by the symplectic step's bounded
    // oscillation.
    let grid = VoxelGrid::filled(GridDims::new(3, 4, 5), MaterialId(0));
    let palette = Palette(vec![Material::new("rubber", E, NU)]);
    let scene = DynamicScene {
        poisson,
        ..DynamicScene::free_space(S)
    };
    let mut sim = Simulation::new(&grid, &palette, &scene).unwrap();
    for i in 0..sim.voxel_count() {
        let z = sim.positions()[i].z;
        sim.set_velocity(i, Vec3::new(z * 2.0, 0.0, z * 1.0))
            .unwrap();
    }
    let e0 = sim.energy().total();
    let mut worst: f64 = 0.0;
    for _ in 0..100 {
        sim.run_steps(200).unwrap();
        worst = worst.max((sim.energy().total() - e0).abs() / e0);
    }
    worst
}
#[test]
fn a_body_two_voxels_thick_is_unchanged_by_the_coupling() {
    // No voxel of a 2×20×2 cantilever has links on both sides across the beam, so the coupling
    // must leave it exactly as it was: bending a thin section must not lock.
    let grid = VoxelGrid::filled(GridDims::new(2, 20, 2), MaterialId(0));
    let palette = Palette(vec![Material::new("rubber", E, NU)]);
    let run = |poisson: bool| {
        let mut sim = Simulation::new(
            &grid,
            &palette,
            &DynamicScene {
                poisson,
                gravity: 9.81,
                floor: None,
                ..DynamicScene::free_space(S)
            },
        )
        .unwrap();
        for k in 0..4 {
            let fixed = sim.voxel_at([k % 2, 0, k / 2]).unwrap();
            sim.fix_voxel(fixed).unwrap();
        }
        sim.run_steps(2000).unwrap();
        (sim.dt(), sim.passes().to_vec(), sim.positions().to_vec())
    };
    assert_eq!(run(true), run(false));
}
