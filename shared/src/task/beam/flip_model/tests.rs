use super::*;
use crate::material::{MaterialId, link_youngs_modulus};
use crate::voxel::GridDims;

const HARD: Option<MaterialId> = Some(MaterialId(0));
const SOFT: Option<MaterialId> = Some(MaterialId(1));

fn beam() -> BeamScene {
    toml::from_str("target = \"circular_arc\"").expect("a beam scene")
}

/// The linked cantilever's normalized profile computed from scratch, by the textbook sums
/// (centroid first, then the second moment about it), not by the model's running sums.
fn direct_profile(scene: &BeamScene, design: &VoxelGrid) -> Vec<f64> {
    let dims = design.dims();
    let moduli = |a: MaterialId, b: MaterialId| {
        let (a, b) = (scene.palette.get(a), scene.palette.get(b));
        (
            link_youngs_modulus(a.youngs_modulus, b.youngs_modulus),
            link_youngs_modulus(a.shear_modulus(), b.shear_modulus()),
        )
    };
    let segments: Vec<(f64, f64)> = (1..dims.ny)
        .map(|s| {
            let links: Vec<(f64, f64, f64)> = (0..dims.nx)
                .flat_map(|x| (0..dims.nz).map(move |z| (x, z)))
                .filter_map(|(x, z)| {
                    let (a, b) = (design.get(x, s - 1, z)?, design.get(x, s, z)?);
                    let (e, g) = moduli(a, b);
                    Some((e, g, z as f64))
                })
                .collect();
            let e: f64 = links.iter().map(|l| l.0).sum();
            let centroid = links.iter().map(|l| l.0 * l.2).sum::<f64>() / e;
            let ei: f64 = (links.iter())
                .map(|&(e, _, z)| e * ((z - centroid).powi(2) + 1.0 / 12.0))
                .sum();
            let ga: f64 = links.iter().map(|l| l.1).sum::<f64>() * SHEAR_COEFFICIENT;
            (1.0 / ei, 1.0 / ga)
        })
        .collect();
    let tip = dims.ny - 1;
    let w = |j: usize| -> f64 {
        (1..=j)
            .map(|s| {
                let middle = s as f64 - 0.5;
                let (bend, shear) = segments[s - 1];
                bend * (tip as f64 - middle) * (j as f64 - middle) + shear
            })
            .sum()
    };
    (0..=tip).map(|j| w(j) / w(tip)).collect()
}

/// Metrics whose measured profile is `deflection`, against `target`.
fn metrics(deflection: &[f64], target: impl Fn(f64) -> f64) -> BeamMetrics {
    let tip = (deflection.len() - 1) as f64;
    BeamMetrics {
        rms_percent: 0.0,
        tip_deflection: 1e-3,
        voxels: 0,
        material_counts: vec![],
        surface_voxels: 0,
        profile: (deflection.iter().enumerate())
            .map(|(j, &w)| [j as f64 / tip, w, target(j as f64 / tip)])
            .collect(),
        solver_iterations: 0,
        solver_residual: 0.0,
    }
}

/// A tapered, two-material design: every layer filled to a height that falls along the beam,
/// with a hard core in the first third.
fn tapered(dims: GridDims) -> VoxelGrid {
    let mut grid = VoxelGrid::empty(dims);
    for y in 0..dims.ny {
        let height = dims.nz - (dims.nz - 2) * y / dims.ny;
        for x in 0..dims.nx {
            for z in 0..height {
                let core = y < dims.ny / 3 && z >= 1 && z + 1 < height && x >= 1 && x + 1 < dims.nx;
                grid.set(x, y, z, if core { HARD } else { SOFT });
            }
        }
    }
    grid
}

/// A full rectangular section of one material has EI = E b h³ / 12 about its centre and
/// κGA = κ G b h: the running sums over its links give the textbook values.
#[test]
fn a_full_section_has_the_textbook_stiffnesses() {
    let scene = beam();
    let dims = GridDims::new(5, 4, 7);
    let grid = VoxelGrid::filled(dims, MaterialId(1));
    let profile = direct_profile(&scene, &grid);
    let model = BeamFlipModel::new(&scene, &grid, &metrics(&profile, |t| t)).expect("a model");
    let soft = scene.palette.get(MaterialId(1));
    let (b, h) = (5.0_f64, 7.0_f64);
    let (bend, shear) = model.compliance[2];
    assert!((bend * soft.youngs_modulus * b * h.powi(3) / 12.0 - 1.0).abs() < 1e-12);
    assert!((shear * SHEAR_COEFFICIENT * soft.shear_modulus() * b * h - 1.0).abs() < 1e-12);
}

/// The gain the model predicts for a flip is the fall of the sum of squares that the layered
/// cantilever, rebuilt from scratch for the flipped design, gives: the incremental update (two
/// segments, the renormalization by the tip) is exact within the model, for every kind of flip.
#[test]
fn a_predicted_gain_is_the_rebuilt_models_change() {
    let scene = beam();
    let dims = GridDims::new(4, 12, 6);
    let grid = tapered(dims);
    let profile = direct_profile(&scene, &grid);
    let target = |t: f64| t.powf(1.7);
    let model = BeamFlipModel::new(&scene, &grid, &metrics(&profile, target)).expect("a model");
    let squares = |p: &[f64]| -> f64 {
        let tip = (p.len() - 1) as f64;
        (p.iter().enumerate().skip(1))
            .map(|(j, w)| (w - target(j as f64 / tip)).powi(2))
            .sum()
    };
    let before = squares(&profile);
    let mut checked = 0;
    for &cell in &grid.boundary_cells() {
        for to in [None, HARD, SOFT] {
            if to == grid.cells()[cell] {
                continue;
            }
            let mut flipped = grid.clone();
            let [x, y, z] = dims.coords(cell);
            flipped.set(x, y, z, to);
            let gain = model.gain(cell, to);
            let linked = |s: usize| {
                (0..dims.nx).any(|x| {
                    (0..dims.nz).any(|z| {
                        flipped.get(x, s - 1, z).is_some() && flipped.get(x, s, z).is_some()
                    })
                })
            };
            let cut = (y >= 1 && !linked(y)) || (y + 1 < dims.ny && !linked(y + 1));
            if cut {
                assert_eq!(gain, f64::NEG_INFINITY);
                continue;
            }
            let rebuilt = before - squares(&direct_profile(&scene, &flipped));
            assert!(
                (gain - rebuilt).abs() <= 1e-9 * before,
                "cell {cell} to {to:?}: predicted {gain}, rebuilt {rebuilt}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked} flips checked");
}

/// Where the measured profile is the target, no flip can improve it: every gain is at most zero
/// (a sum of squares at its minimum).
#[test]
fn on_target_no_flip_helps() {
    let scene = beam();
    let grid = tapered(GridDims::new(4, 10, 5));
    let profile = direct_profile(&scene, &grid);
    let tip = (profile.len() - 1) as f64;
    let target = |t: f64| profile[(t * tip).round() as usize];
    let model = BeamFlipModel::new(&scene, &grid, &metrics(&profile, target)).expect("a model");
    for &cell in &grid.boundary_cells() {
        for to in [None, HARD, SOFT] {
            if to != grid.cells()[cell] {
                assert!(model.gain(cell, to) <= 0.0, "cell {cell} to {to:?}");
            }
        }
    }
}

/// A profile that bends too little near the clamp and too much near the tip asks for a softer
/// root and a stiffer tip: carving a top voxel is predicted to help at the root and hurt at the
/// tip, hardening one the reverse (the beam's moment is largest at the root).
#[test]
fn the_error_picks_the_end_to_soften() {
    let scene = beam();
    let dims = GridDims::new(3, 12, 6);
    let mut grid = VoxelGrid::empty(dims);
    for y in 0..dims.ny {
        for x in 0..dims.nx {
            for z in 0..4 {
                grid.set(x, y, z, SOFT);
            }
        }
    }
    let profile = direct_profile(&scene, &grid);
    // A target deflecting more at every inner station than the measured shape: more curvature
    // near the clamp, less near the tip.
    let tip = (dims.ny - 1) as f64;
    let target = |t: f64| profile[(t * tip).round() as usize].powf(0.8);
    let model = BeamFlipModel::new(&scene, &grid, &metrics(&profile, target)).expect("a model");
    let top = |y| dims.index(1, y, 3);
    assert!(model.gain(top(1), None) > 0.0, "carving at the root helps");
    assert!(
        model.gain(top(1), HARD) < 0.0,
        "hardening at the root hurts"
    );
    assert!(model.gain(top(10), None) < 0.0, "carving at the tip hurts");
    assert!(
        model.gain(top(10), HARD) > 0.0,
        "hardening at the tip helps"
    );
}

/// A hard voxel among soft ones stiffens its links in series with soft halves, about twofold,
/// not by the materials' thousandfold: the model's segment stiffens as the solver's links do.
#[test]
fn a_lone_hard_voxel_stiffens_its_links_in_series() {
    let scene = beam();
    let dims = GridDims::new(1, 6, 1);
    let grid = VoxelGrid::filled(dims, MaterialId(1));
    let profile = direct_profile(&scene, &grid);
    let mut model = BeamFlipModel::new(&scene, &grid, &metrics(&profile, |t| t)).expect("a model");
    let soft = model.compliance[3].0;
    model.take(dims.index(0, 3, 0), HARD);
    let (e_hard, e_soft) = (1.0e9, 1.0e6);
    let series = 2.0 * e_hard * e_soft / (e_hard + e_soft) / e_soft;
    for s in [3, 4] {
        assert!(
            (soft / model.compliance[s].0 - series).abs() < 1e-9,
            "segment {s}"
        );
    }
    assert_eq!(model.compliance[2].0, soft, "a segment the voxel is not in");
}

/// A profile without a station at every layer (another resolution's) gives no model.
#[test]
fn a_profile_of_another_resolution_gives_no_model() {
    let scene = beam();
    let grid = tapered(GridDims::new(4, 10, 5));
    let profile = direct_profile(&scene, &grid);
    assert!(BeamFlipModel::new(&scene, &grid, &metrics(&profile[..8], |t| t)).is_none());
}

/// A flip taken leaves the model the one rebuilt from scratch for the flipped design, measured
/// as the model predicts: every later gain agrees with the rebuilt model's, so a sequence of
/// taken flips is exact within the model however long it is.
#[test]
fn a_taken_flip_leaves_the_rebuilt_model() {
    let scene = beam();
    let dims = GridDims::new(4, 12, 6);
    let mut grid = tapered(dims);
    let target = |t: f64| t.powf(1.7);
    let profile = direct_profile(&scene, &grid);
    let original = grid.clone();
    let mut model =
        BeamFlipModel::new(&scene, &original, &metrics(&profile, target)).expect("a model");
    let boundary = original.boundary_cells();
    for (k, &cell) in boundary.iter().step_by(7).take(6).enumerate() {
        let to = [None, HARD, SOFT][k % 3];
        let to = if to == grid.cells()[cell] {
            SOFT.filter(|_| to != SOFT).or(HARD)
        } else {
            to
        };
        model.take(cell, to);
        let [x, y, z] = dims.coords(cell);
        grid.set(x, y, z, to);
        let rebuilt_profile = direct_profile(&scene, &grid);
        let rebuilt =
            BeamFlipModel::new(&scene, &grid, &metrics(&rebuilt_profile, target)).expect("a model");
        assert!(
            (model.squares - rebuilt.squares).abs() <= 1e-12,
            "after {} flips",
            k + 1
        );
        for &other in boundary.iter().step_by(5) {
            for to in [None, HARD, SOFT] {
                if to == grid.cells()[other] {
                    continue;
                }
                let (a, b) = (model.gain(other, to), rebuilt.gain(other, to));
                assert!(
                    a == b || (a - b).abs() <= 1e-9 * model.squares.max(1e-12),
                    "after {} flips, cell {other} to {to:?}: {a} against {b}",
                    k + 1
                );
            }
        }
    }
}
