//! The genome: a Gaussian mixture, a list of points in normalized workspace units.

use serde::{Deserialize, Serialize};

use crate::material::MaterialId;

/// One Gaussian point of the mixture (paper §I-D): it adds `density · exp(−d²/(2 falloff²))` to
/// its material's density field at distance `d` from `position`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianPoint {
    /// Position in normalized workspace units, each coordinate in [0, 1].
    pub position: [f64; 3],
    /// Signed peak density; negative points carve material away.
    pub density: f64,
    /// Standard deviation σ of the Gaussian, in units of the workspace's longest side.
    pub falloff: f64,
    /// Which material of the scene's palette this point feeds.
    pub material: MaterialId,
}

/// A design: the ordered list of Gaussian points. The order matters only for bit-exact
/// reproducibility (density sums are accumulated in point order).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Genome {
    pub points: Vec<GaussianPoint>,
}

/// The ranges a genome's parameters live in; random initialisation and mutation stay inside them
/// and [`Genome::validate`] rejects anything outside.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GenomeLimits {
    /// Lowest and highest signed density of a point.
    pub density: [f64; 2],
    /// Smallest and largest falloff σ (units of the workspace's longest side). The lower bound keeps
    /// a point from vanishing between voxel centres at coarse resolutions.
    pub falloff: [f64; 2],
    /// Most points a genome may hold; protects workers from oversized requests.
    pub max_points: usize,
    /// Fewest points a genome keeps when mutation removes points.
    pub min_points: usize,
}

impl Default for GenomeLimits {
    fn default() -> Self {
        Self {
            density: [-1.0, 1.0],
            falloff: [0.02, 0.4],
            max_points: 1000,
            min_points: 1,
        }
    }
}

impl GenomeLimits {
    /// Checks the limits themselves, naming the offending field.
    pub fn validate(&self) -> Result<(), GenomeError> {
        let range_ok = |r: [f64; 2]| r[0].is_finite() && r[1].is_finite() && r[0] < r[1];
        if !range_ok(self.density) {
            return Err(GenomeError::Limits("density"));
        }
        if !range_ok(self.falloff) || self.falloff[0] <= 0.0 {
            return Err(GenomeError::Limits("falloff"));
        }
        if self.max_points == 0 || self.min_points > self.max_points {
            return Err(GenomeError::Limits("max_points"));
        }
        Ok(())
    }
}

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum GenomeError {
    #[error("genome has {count} points, more than the limit of {max}")]
    TooManyPoints { count: usize, max: usize },
    #[error("point {point}: {field} = {value} is not finite")]
    NotFinite {
        point: usize,
        field: &'static str,
        value: f64,
    },
    #[error("point {point}: {field} = {value} is outside [{min}, {max}]")]
    OutOfRange {
        point: usize,
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("point {point}: material {material} is unknown (the scene has {count} materials)")]
    UnknownMaterial {
        point: usize,
        material: u8,
        count: usize,
    },
    #[error("genome limits: {0} is not a valid range")]
    Limits(&'static str),
}

impl Genome {
    pub fn new(points: Vec<GaussianPoint>) -> Self {
        Self { points }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Rejects non-finite or out-of-range values, unknown materials and oversized genomes, naming
    /// the first offending point and field.
    pub fn validate(
        &self,
        limits: &GenomeLimits,
        material_count: usize,
    ) -> Result<(), GenomeError> {
        if self.points.len() > limits.max_points {
            return Err(GenomeError::TooManyPoints {
                count: self.points.len(),
                max: limits.max_points,
            });
        }
        for (i, p) in self.points.iter().enumerate() {
            let check = |field: &'static str, value: f64, [min, max]: [f64; 2]| {
                if !value.is_finite() {
                    Err(GenomeError::NotFinite {
                        point: i,
                        field,
                        value,
                    })
                } else if value < min || value > max {
                    Err(GenomeError::OutOfRange {
                        point: i,
                        field,
                        value,
                        min,
                        max,
                    })
                } else {
                    Ok(())
                }
            };
            check("x", p.position[0], [0.0, 1.0])?;
            check("y", p.position[1], [0.0, 1.0])?;
            check("z", p.position[2], [0.0, 1.0])?;
            check("density", p.density, limits.density)?;
            check("falloff", p.falloff, limits.falloff)?;
            if p.material.index() >= material_count {
                return Err(GenomeError::UnknownMaterial {
                    point: i,
                    material: p.material.0,
                    count: material_count,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
