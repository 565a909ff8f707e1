//! How one voxel's change of state is expected to move a beam's profile error: a one-dimensional
//! Timoshenko cantilever built from the links between the design's layers, fed with the profile
//! the static solve measured. A search can then change the voxels the error asks for instead of
//! random ones on the design's boundary.
//!
//! The segment between layers y − 1 and y is the bundle of links joining their filled voxels
//! column by column, each with the series modulus of its two voxels (`link_youngs_modulus`, as
//! the solver stiffens it): so a lone hard voxel in soft surroundings stiffens its links about
//! twofold, not a thousandfold. Each segment has a bending stiffness EI about its modulus-weighted
//! centroid and a shear stiffness κGA; it bends under the tip load's moment at its midpoint, and
//! every station beyond it deflects by that rotation times its distance plus the segment's shear.
//! A flip changes the two segments either side of its voxel, so its effect on every station is a
//! few multiplications, and the profile normalized by the tip's (what the fitness compares)
//! follows exactly within the model. The model only ranks candidate flips; the static solve still
//! judges every child.

use super::scene::{BeamMetrics, BeamScene};
use crate::material::{MaterialId, link_youngs_modulus};
use crate::task::FlipModel;
use crate::voxel::VoxelGrid;

/// Timoshenko's shear coefficient of a rectangular section.
const SHEAR_COEFFICIENT: f64 = 5.0 / 6.0;

/// One segment's sums over its links, lengths in voxels: Σ E, Σ E z, Σ E (z² + 1/12), Σ G.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Section {
    e: f64,
    e_z: f64,
    e_zz: f64,
    g: f64,
}

impl Section {
    fn add(&mut self, sign: f64, (e, g): (f64, f64), z: f64) {
        self.e += sign * e;
        self.e_z += sign * e * z;
        self.e_zz += sign * e * (z * z + 1.0 / 12.0);
        self.g += sign * g;
    }

    /// Bending and shear compliance per unit load and length, or `None` for a segment without
    /// links (the beam cut in two).
    fn compliances(&self) -> Option<(f64, f64)> {
        // A flip can leave rounding's dust in an emptied segment's sums; a link's E is far above it.
        if self.e <= 1e-9 * self.e_zz.abs().max(1.0) || self.g <= 0.0 {
            return None;
        }
        let ei = self.e_zz - self.e_z * self.e_z / self.e;
        (ei > 0.0).then(|| (1.0 / ei, 1.0 / (SHEAR_COEFFICIENT * self.g)))
    }
}

/// A segment's new sums and compliances after a flip.
type Changed = (usize, Section, (f64, f64));

/// A beam design's flip model: its segments' sections and compliances, the measured profile and
/// the target, and the model's own tip deflection that normalizes a predicted change.
#[derive(Debug)]
pub struct BeamFlipModel<'a> {
    design: &'a VoxelGrid,
    /// The design's states with the flips taken so far ([`FlipModel::take`]).
    cells: Vec<Option<MaterialId>>,
    /// (E, G) of each material.
    moduli: Vec<(f64, f64)>,
    /// Segment s joins layers s − 1 and s (index 0 unused).
    sections: Vec<Section>,
    /// Each segment's (bending, shear) compliance.
    compliance: Vec<(f64, f64)>,
    /// Measured normalized deflection less the target, stations 0..=tip (0 is the clamp).
    residual: Vec<f64>,
    /// Measured normalized deflection, same stations.
    deflection: Vec<f64>,
    /// The model's tip deflection per unit load.
    tip: f64,
    /// The measured profile's sum of squares.
    squares: f64,
}

impl<'a> BeamFlipModel<'a> {
    /// The model of `design` (kept, at the resolution `metrics` were measured at), or `None` when
    /// the profile does not have a station at every layer or a segment has no links.
    pub fn new(scene: &BeamScene, design: &'a VoxelGrid, metrics: &BeamMetrics) -> Option<Self> {
        let dims = design.dims();
        if dims.ny < 2 || metrics.profile.len() != dims.ny {
            return None;
        }
        let moduli: Vec<(f64, f64)> = (scene.palette.iter())
            .map(|(_, m)| (m.youngs_modulus, m.shear_modulus()))
            .collect();
        let deflection: Vec<f64> = metrics.profile.iter().map(|p| p[1]).collect();
        let residual: Vec<f64> = metrics.profile.iter().map(|p| p[1] - p[2]).collect();
        let squares = residual[1..].iter().map(|r| r * r).sum();
        let mut model = Self {
            design,
            cells: design.cells().to_vec(),
            moduli,
            sections: vec![Section::default(); dims.ny],
            compliance: vec![(0.0, 0.0); dims.ny],
            residual,
            deflection,
            tip: 0.0,
            squares,
        };
        for s in 1..dims.ny {
            for x in 0..dims.nx {
                for z in 0..dims.nz {
                    let link = model.link(dims.index(x, s - 1, z), dims.index(x, s, z))?;
                    if let Some(link) = link {
                        model.sections[s].add(1.0, link, z as f64);
                    }
                }
            }
            model.compliance[s] = model.sections[s].compliances()?;
        }
        model.tip = model.tip_deflection();
        (model.tip.is_finite() && model.tip > 0.0).then_some(model)
    }

    fn tip_layer(&self) -> usize {
        self.sections.len() - 1
    }

    /// The (E, G) of the link between cells `a` and `b` in their current states: `Some(None)`
    /// where either is empty, `None` for a material the palette lacks.
    fn link(&self, a: usize, b: usize) -> Option<Option<(f64, f64)>> {
        self.link_with(a, b, usize::MAX, None)
    }

    /// Segment `s` under the tip load, with `changed` in place of its own compliances where it is
    /// one of them: its bending compliance times its moment, and its shear compliance.
    fn segment(&self, s: usize, changed: &[Changed]) -> (f64, f64) {
        let (bend, shear) = (changed.iter())
            .find(|c| c.0 == s)
            .map_or(self.compliance[s], |c| c.2);
        let moment = self.tip_layer() as f64 - (s as f64 - 0.5);
        (bend * moment, shear)
    }

    fn tip_deflection(&self) -> f64 {
        let tip = self.tip_layer() as f64;
        (1..=self.tip_layer())
            .map(|s| {
                let (bend, shear) = self.segment(s, &[]);
                bend * (tip - (s as f64 - 0.5)) + shear
            })
            .sum()
    }

    /// The normalized deflection the model predicts at every station (the clamp's included) with
    /// the segments `changed`, in station order, and the model's tip deflection's factor of
    /// change. Lazy: a gain only sums it, and the greedy sequence asks for thousands an epoch.
    fn predicted_profile(&self, changed: &[Changed]) -> (impl Iterator<Item = f64> + '_, f64) {
        let tip = self.tip_layer();
        // A changed segment's change of rotation and shear moves every station beyond it.
        let changes: Vec<(usize, f64, f64)> = (changed.iter())
            .map(|&(s, _, _)| {
                let (b0, s0) = self.segment(s, &[]);
                let (b1, s1) = self.segment(s, changed);
                (s, b1 - b0, s1 - s0)
            })
            .collect();
        let shift = move |j: usize| -> f64 {
            (changes.iter())
                .filter(|&&(s, _, _)| s <= j)
                .map(|&(s, bend, shear)| bend * (j as f64 - (s as f64 - 0.5)) + shear)
                .sum::<f64>()
                / self.tip
        };
        let scale = 1.0 + shift(tip);
        let profile = (0..=tip).map(move |j| (self.deflection[j] + shift(j)) / scale);
        (profile, scale)
    }

    /// The segments either side of `cell` once it takes the state `to`; `None` when that would
    /// leave one without links (or names a material the palette lacks).
    fn flipped(&self, cell: usize, to: Option<MaterialId>) -> Option<Vec<Changed>> {
        let dims = self.design.dims();
        let [x, y, z] = dims.coords(cell);
        let segments = [y, y + 1]
            .into_iter()
            .filter(|&s| s >= 1 && s <= self.tip_layer());
        let mut changed = Vec::with_capacity(2);
        for s in segments {
            let (a, b) = (dims.index(x, s - 1, z), dims.index(x, s, z));
            let mut section = self.sections[s];
            if let Some(old) = self.link(a, b)? {
                section.add(-1.0, old, z as f64);
            }
            if let Some(new) = self.link_with(a, b, cell, to)? {
                section.add(1.0, new, z as f64);
            }
            changed.push((s, section, section.compliances()?));
        }
        Some(changed)
    }

    /// [`Self::link`] with `cell` in the state `to`.
    fn link_with(
        &self,
        a: usize,
        b: usize,
        cell: usize,
        to: Option<MaterialId>,
    ) -> Option<Option<(f64, f64)>> {
        let state = |i: usize| if i == cell { to } else { self.cells[i] };
        let (Some(ma), Some(mb)) = (state(a), state(b)) else {
            return Some(None);
        };
        let (ea, ga) = *self.moduli.get(ma.index())?;
        let (eb, gb) = *self.moduli.get(mb.index())?;
        Some(Some((
            link_youngs_modulus(ea, eb),
            link_youngs_modulus(ga, gb),
        )))
    }

    /// The sum of squares against the target of `profile`, every station's deflection from the
    /// clamp's on (the clamp's own is not counted).
    fn squares_of(&self, profile: impl Iterator<Item = f64>) -> f64 {
        (profile.enumerate().skip(1))
            .map(|(j, w)| {
                let target = self.deflection[j] - self.residual[j];
                (w - target).powi(2)
            })
            .sum()
    }
}

impl FlipModel for BeamFlipModel<'_> {
    /// The predicted fall of the profile's sum of squares (minus the fitness) when `cell` takes
    /// the state `to`; minus infinity for a flip that would cut the beam.
    fn gain(&self, cell: usize, to: Option<MaterialId>) -> f64 {
        match self.flipped(cell, to) {
            Some(changed) => self.squares - self.squares_of(self.predicted_profile(&changed).0),
            None => f64::NEG_INFINITY,
        }
    }

    /// The flip made: the segments' sections, the predicted profile (renormalized by its tip)
    /// and the model's tip deflection become the ones `gain` predicted.
    fn take(&mut self, cell: usize, to: Option<MaterialId>) {
        let Some(changed) = self.flipped(cell, to) else {
            return;
        };
        let (profile, scale) = self.predicted_profile(&changed);
        let profile: Vec<f64> = profile.collect();
        for (j, w) in profile.into_iter().enumerate() {
            let target = self.deflection[j] - self.residual[j];
            self.deflection[j] = w;
            self.residual[j] = w - target;
        }
        self.squares = self.squares_of(self.deflection.iter().copied());
        self.tip *= scale;
        for (s, section, compliance) in changed {
            self.sections[s] = section;
            self.compliance[s] = compliance;
        }
        self.cells[cell] = to;
    }
}

#[cfg(test)]
#[path = "flip_model/tests.rs"]
mod tests;
