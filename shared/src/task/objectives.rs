//! What a multi-objective search may trade off: each task names its objectives (a beam's RMS error
//! against its hard material, a robot's speed against its size), says whether more or less is
//! better, and computes their values from a design's metrics at the resolution it was evaluated.
//! The measures shared by several tasks (how much hard material, mass, actuated volume) are here.

use crate::material::Palette;

/// Whether a larger or a smaller value of an objective is better.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sense {
    Minimize,
    Maximize,
}

/// One objective of a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Objective {
    /// Its name in `[search] objectives` and in `pareto.csv`'s header.
    pub name: &'static str,
    pub sense: Sense,
    /// The unit of its value ("%", "kg", "" for a count or a fraction).
    pub unit: &'static str,
    /// What it measures, for the docs and the report.
    pub about: &'static str,
}

impl Objective {
    /// `value` as a quantity to minimize: itself, or its negative for a maximized objective.
    pub fn minimized(&self, value: f64) -> f64 {
        match self.sense {
            Sense::Minimize => value,
            Sense::Maximize => -value,
        }
    }
}

/// The palette's stiffest material (the lowest index among equals): the "hard" one of a beam's
/// soft/hard pair.
pub fn stiffest(palette: &Palette) -> usize {
    let mut best = 0;
    for (id, m) in palette.iter() {
        if m.youngs_modulus > palette.0[best].youngs_modulus {
            best = id.index();
        }
    }
    best
}

/// The share of the workspace's `cells` filled with material `material`.
pub fn fraction_of_cells(material_counts: &[usize], material: usize, cells: usize) -> f64 {
    material_counts.get(material).copied().unwrap_or(0) as f64 / cells as f64
}

/// The design's mass, kg: each material's voxel count times its density times the voxel volume
/// (`voxel_size` in m).
pub fn mass(material_counts: &[usize], palette: &Palette, voxel_size: f64) -> f64 {
    let volume = voxel_size.powi(3);
    (material_counts.iter().zip(&palette.0))
        .map(|(&count, m)| count as f64 * m.density * volume)
        .sum()
}

/// The share of the design's voxels made of an actuated material.
pub fn actuated_fraction(material_counts: &[usize], palette: &Palette) -> f64 {
    let voxels: usize = material_counts.iter().sum();
    let actuated: usize = (material_counts.iter().zip(&palette.0))
        .filter(|(_, m)| m.actuated)
        .map(|(&count, _)| count)
        .sum();
    if voxels == 0 {
        0.0
    } else {
        actuated as f64 / voxels as f64
    }
}

#[cfg(test)]
mod tests;
