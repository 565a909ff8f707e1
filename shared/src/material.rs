//! Materials: the per-voxel physical properties the genome's material index selects.
//!
//! A genome names materials by index into a [`Palette`]; the palette belongs to the scene, so the
//! same genome can be evaluated with other materials (the paper's hard/soft resins for beams, a
//! passive and an actuated foam for robots).

use serde::{Deserialize, Serialize};

/// Index of a material in a scene's [`Palette`]; a newtype so it cannot be swapped with a count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct MaterialId(pub u8);

impl MaterialId {
    pub fn index(self) -> usize {
        usize::from(self.0)
    }
}

/// A linear isotropic material, as the paper's static and dynamic analyses assume.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Human-readable name, used in exports and reports.
    pub name: String,
    /// Young's modulus E in Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, dimensionless, in [0, 0.5).
    pub poisson_ratio: f64,
    /// Mass density ρ in kg/m³.
    #[serde(default = "default_density")]
    pub density: f64,
    /// Coefficient of static friction against the floor (dimensionless).
    #[serde(default = "default_static_friction")]
    pub static_friction: f64,
    /// Coefficient of kinetic friction against the floor (dimensionless).
    #[serde(default = "default_kinetic_friction")]
    pub kinetic_friction: f64,
    /// Whether links made of this material follow the scene's volumetric actuation.
    #[serde(default)]
    pub actuated: bool,
    /// Display colour as RGB, for renders and exports.
    #[serde(default = "default_colour")]
    pub colour: [u8; 3],
}

fn default_density() -> f64 {
    1000.0
}
fn default_static_friction() -> f64 {
    1.0
}
fn default_kinetic_friction() -> f64 {
    0.3
}
fn default_colour() -> [u8; 3] {
    [128, 128, 128]
}

impl Material {
    /// A material with the given stiffness and Poisson's ratio and defaults elsewhere.
    pub fn new(name: &str, youngs_modulus: f64, poisson_ratio: f64) -> Self {
        Self {
            name: name.to_owned(),
            youngs_modulus,
            poisson_ratio,
            density: default_density(),
            static_friction: default_static_friction(),
            kinetic_friction: default_kinetic_friction(),
            actuated: false,
            colour: default_colour(),
        }
    }

    /// Shear modulus G = E / (2(1 + ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Checks that every property is finite and physically meaningful.
    pub fn validate(&self) -> Result<(), MaterialError> {
        let field = |name: &'static str, value: f64, ok: bool| {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(MaterialError::Invalid {
                    material: self.name.clone(),
                    field: name,
                    value,
                })
            }
        };
        field(
            "youngs_modulus",
            self.youngs_modulus,
            self.youngs_modulus > 0.0,
        )?;
        field(
            "poisson_ratio",
            self.poisson_ratio,
            (0.0..0.5).contains(&self.poisson_ratio),
        )?;
        field("density", self.density, self.density > 0.0)?;
        field(
            "static_friction",
            self.static_friction,
            self.static_friction >= 0.0,
        )?;
        field(
            "kinetic_friction",
            self.kinetic_friction,
            self.kinetic_friction >= 0.0 && self.kinetic_friction <= self.static_friction,
        )?;
        Ok(())
    }
}

/// Young's modulus of a link joining two materials: the series (harmonic) combination
/// 2E₁E₂/(E₁+E₂), which is exact for two half-links of equal length in series.
pub fn link_youngs_modulus(e1: f64, e2: f64) -> f64 {
    2.0 * e1 * e2 / (e1 + e2)
}

/// The materials a scene offers, indexed by [`MaterialId`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Palette(pub Vec<Material>);

impl Palette {
    /// Most materials a palette may hold (a genome stores the index in a byte).
    pub const MAX_MATERIALS: usize = 16;

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn get(&self, id: MaterialId) -> &Material {
        &self.0[id.index()]
    }

    pub fn iter(&self) -> impl Iterator<Item = (MaterialId, &Material)> {
        self.0
            .iter()
            .enumerate()
            .map(|(i, m)| (MaterialId(i as u8), m))
    }

    pub fn validate(&self) -> Result<(), MaterialError> {
        if self.0.is_empty() || self.0.len() > Self::MAX_MATERIALS {
            return Err(MaterialError::PaletteSize(self.0.len()));
        }
        self.0.iter().try_for_each(Material::validate)
    }

    /// The paper's beam materials: a hard and a soft printing resin about 1000:1 in stiffness
    /// (VeroGrey-like 1 GPa, TangoPlus-like 1 MPa).
    pub fn hard_soft_resins() -> Self {
        let mut hard = Material::new("hard resin", 1.0e9, 0.35);
        hard.density = 1180.0;
        hard.colour = [90, 90, 100];
        let mut soft = Material::new("soft resin", 1.0e6, 0.45);
        soft.density = 1120.0;
        soft.colour = [235, 200, 60];
        Self(vec![hard, soft])
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MaterialError {
    #[error("material '{material}': {field} = {value} is out of range")]
    Invalid {
        material: String,
        field: &'static str,
        value: f64,
    },
    #[error("a palette holds 1 to {max} materials, got {0}", max = Palette::MAX_MATERIALS)]
    PaletteSize(usize),
}

#[cfg(test)]
mod tests;
