//! The dynamic scene: every physical and numerical parameter of a simulation, with units,
//! defaults and trade-offs, validated once. The scene decides which passes the step loop has.

use serde::{Deserialize, Serialize};

use super::error::{DynamicsError, Result};
use crate::material::{Material, Palette};

/// Everything a dynamic simulation needs besides the voxels and their materials.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DynamicScene {
    /// Edge length s of a voxel, m. Default 1e-3 (a 20-voxel robot is ~18–20 mm, as in the
    /// paper's Table IV). Smaller voxels make the time step shorter (dt ∝ s for fixed E, ρ).
    pub voxel_size: f64,
    /// Gravitational acceleration along −Z, m/s². Default 9.81; 0 removes the gravity pass.
    pub gravity: f64,
    /// The floor at z = 0, or none (free space).
    pub floor: Option<Floor>,
    /// Self-collision between non-adjacent surface voxels. Default false (costs a spatial-hash
    /// rebuild per step).
    pub collisions: bool,
    /// Lateral Poisson coupling: a voxel stretched along one axis contracts along the others by
    /// its material's ν (see `poisson.rs`). Default false. On, a bulk body has Young's modulus E
    /// and lateral contraction ν in its interior (test `dynamics_poisson`); only axes along which
    /// a voxel has links on both sides couple, so a section one or two voxels thick behaves as
    /// without the coupling and does not lock in bending. It stiffens confined links to the
    /// P-wave modulus (1.60 E at ν = 0.35), shortening the automatic time step by 1/√1.60 = 0.79,
    /// and adds a pass. Off, ν enters only the shear and torsion stiffness (G = E/(2(1+ν))) and
    /// the lattice's effective Poisson's ratio is 0.
    pub poisson: bool,
    /// Volumetric actuation of the palette's actuated materials, or none.
    pub actuation: Option<Actuation>,
    /// Damping of every kind, as ratios of critical damping.
    pub damping: DampingParams,
    /// Time-step fraction f in dt = f / (2π √(k_max / m_min)), dimensionless. Default 1.0.
    /// Undamped, the symplectic Euler scheme is stable up to f ≈ 3.4 on a dense block (top mode
    /// ω_top² ≈ 13.1 k/m, h = ω_top dt < 2); with damping ratio ζ on that mode it needs
    /// h² + 4ζh ≤ 4 (f ≈ 1.4 at ζ = 1, by this mode analysis). Smaller f buys accuracy with proportionally more steps.
    pub dt_fraction: f64,
    /// When a run counts as diverged.
    pub divergence: DivergenceLimits,
    /// The link kernel's arithmetic. Default `double`, the arithmetic of every result before it;
    /// not written when default, so earlier scenes encode to the same bytes.
    #[serde(skip_serializing_if = "LinkPrecision::is_default")]
    pub link_precision: LinkPrecision,
}

/// How the link kernel computes (docs/explanation/physics.md). Either way the state is
/// `f64`, integrated in `f64`, and a result is the same bits on any x86-64 CPU and any number of
/// threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinkPrecision {
    /// `f64` throughout, four links per vector.
    #[default]
    Double,
    /// The kernel reads an `f32` copy of the state (positions relative to one voxel) and computes
    /// in `f32`, eight links per vector; its forces are summed in `f64`. Faster; moves a random
    /// robot's gait far less than halving the time step does.
    Mixed,
}

impl LinkPrecision {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

impl Default for DynamicScene {
    fn default() -> Self {
        Self {
            voxel_size: 1e-3,
            gravity: 9.81,
            floor: Some(Floor::default()),
            collisions: false,
            poisson: false,
            actuation: None,
            damping: DampingParams::default(),
            dt_fraction: 1.0,
            divergence: DivergenceLimits::default(),
            link_precision: LinkPrecision::Double,
        }
    }
}

/// A rigid, flat floor at z = 0 with penalty contact and Coulomb friction (coefficients come from
/// the voxel's material).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Floor {
    /// Contact stiffness as a multiple of the voxel's own axial link stiffness E·s, dimensionless.
    /// Default 1.0: penetration under a voxel's weight is then ~ρ g s²/E (negligible) and the
    /// stable time step is unchanged. Larger values stiffen contact and shorten the stable step.
    pub stiffness_factor: f64,
    /// Incline of the floor, rad: the floor stays at z = 0 and gravity is tilted by this angle
    /// away from −Z towards `downhill`. Default 0.
    pub incline: f64,
    /// The direction in the floor plane that is downhill, rad from +X towards +Y. Default 0
    /// (downhill is +X).
    pub downhill: f64,
    /// Whether an actuated voxel meets the floor at its actuated size (its underside moves with
    /// its swelling, so a swelling foot pushes the body up), as Voxelyze's floor does, rather than
    /// at its rest size. Default false, the contact of every result before it
    /// (docs/how-to/voxelyze.md); not written when false, so earlier scenes encode to the same
    /// bytes.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub actuated_contact: bool,
    /// The friction law at the floor. Default `sticking`, the law of every result before it; not
    /// written when default, so earlier scenes encode to the same bytes.
    #[serde(skip_serializing_if = "FrictionLaw::is_default")]
    pub friction: FrictionLaw,
}

/// How a voxel on the floor changes between sticking and sliding (docs/explanation/physics.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// A voxel sticks while its tangential pull is within μs·N and starts sliding against kinetic
    /// friction μk·N when it is not; a sliding voxel stops and sticks when friction would stop
    /// it within a step and static friction can hold it. N includes the contact's damping.
    #[default]
    Sticking,
    /// The VoxCAD-era Voxelyze's law, for comparing with that reader: N is the contact's elastic
    /// force alone; a voxel is held only while its velocity is exactly zero and its pull below
    /// μs·N (a stopped voxel pulled harder moves that step without friction); a sliding voxel that
    /// friction would stop within a step is stopped, whatever pulls it.
    Voxcad,
}

impl FrictionLaw {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

impl Default for Floor {
    fn default() -> Self {
        Self {
            stiffness_factor: 1.0,
            incline: 0.0,
            downhill: 0.0,
            actuated_contact: false,
            friction: FrictionLaw::Sticking,
        }
    }
}

/// Sinusoidal volumetric actuation: an actuated voxel's volume follows
/// 1 + amplitude_volume · sin(2π t / period + phase), so its links' rest lengths scale by the cube
/// root of that (per axis).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Actuation {
    /// Relative volume amplitude, dimensionless: 0.2 = ±20 % (the paper's; (1 + a)³ = 1.2 with a
    /// the linear amplitude). Must be in [0, 1).
    pub amplitude_volume: f64,
    /// Period T of one actuation cycle, s. Default 0.07 (the paper's Table IV), slow compared
    /// with the resonance of an 18 mm foam body (~3 ms).
    pub period: f64,
    /// Phase at t = 0 of the actuation clock, rad. Default 0.
    pub phase: f64,
}

impl Default for Actuation {
    fn default() -> Self {
        Self {
            amplitude_volume: 0.2,
            period: 0.07,
            phase: 0.0,
        }
    }
}

/// Damping as ratios of critical damping ζ (0 = none, 1 = critical). A zero ratio removes the
/// corresponding pass (or the damping terms of the link pass) from the step loop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DampingParams {
    /// Internal damping of every link, stiffness-proportional: the damping ratio ζ of the fastest
    /// mode of the voxel lattice (ω_top² ≈ 14·EA/(L m)); a mode of frequency ω gets ζ·ω/ω_top.
    /// Acts on deformation rates only, so rigid motion is not damped. Default 1.0: kills the
    /// high-frequency ringing within a period or two; slow bending modes keep ringing (use
    /// `global` to settle them). The explicit step tolerates up to ζ ≈ 1.5 at `dt_fraction` 1;
    /// larger values need a smaller `dt_fraction`.
    pub link: f64,
    /// Damping of each voxel's absolute velocity against the world, ζ. Default 0: it drags the
    /// whole body and so biases locomotion; useful to settle static scenes quickly.
    pub global: f64,
    /// Damping of the normal velocity of a voxel in floor contact, ζ. Default 1.0: no bouncing.
    pub contact: f64,
}

impl Default for DampingParams {
    fn default() -> Self {
        Self {
            link: 1.0,
            global: 0.0,
            contact: 1.0,
        }
    }
}

/// Limits past which a simulation is declared diverged (checked every step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DivergenceLimits {
    /// Largest axial link strain |ΔL/L|, dimensionless. Default 1.0: a link stretched to twice
    /// or crushed to nothing is no longer a beam.
    pub max_strain: f64,
    /// Largest distance a voxel may travel in one step, in voxel sizes. Default 0.25: an explicit
    /// step cannot resolve contact or links beyond that, so it signals a runaway (kinetic energy).
    pub max_step_travel: f64,
}

impl Default for DivergenceLimits {
    fn default() -> Self {
        Self {
            max_strain: 1.0,
            max_step_travel: 0.25,
        }
    }
}

impl DynamicScene {
    /// The paper's locomotion setup (§IV): floor with gravity, ±20 % volume actuation at a
    /// 0.07 s period. Use it with [`foam_palette`].
    pub fn paper_locomotion() -> Self {
        Self {
            actuation: Some(Actuation::default()),
            ..Self::default()
        }
    }

    /// Free space, no gravity, no floor, no damping: only the link pass remains.
    pub fn free_space(voxel_size: f64) -> Self {
        Self {
            voxel_size,
            gravity: 0.0,
            floor: None,
            damping: DampingParams {
                link: 0.0,
                global: 0.0,
                contact: 0.0,
            },
            ..Self::default()
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        let check = |field: &'static str, value: f64, ok: bool| {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(DynamicsError::InvalidScene { field, value })
            }
        };
        check("voxel_size", self.voxel_size, self.voxel_size > 0.0)?;
        check("gravity", self.gravity, self.gravity >= 0.0)?;
        if let Some(f) = &self.floor {
            check(
                "floor.stiffness_factor",
                f.stiffness_factor,
                f.stiffness_factor > 0.0,
            )?;
            check(
                "floor.incline",
                f.incline,
                f.incline.abs() < std::f64::consts::FRAC_PI_2,
            )?;
            check("floor.downhill", f.downhill, true)?;
        }
        if let Some(a) = &self.actuation {
            check(
                "actuation.amplitude_volume",
                a.amplitude_volume,
                (0.0..1.0).contains(&a.amplitude_volume),
            )?;
            check("actuation.period", a.period, a.period > 0.0)?;
            check("actuation.phase", a.phase, true)?;
        }
        let d = &self.damping;
        check("damping.link", d.link, d.link >= 0.0)?;
        check("damping.global", d.global, d.global >= 0.0)?;
        check("damping.contact", d.contact, d.contact >= 0.0)?;
        check("dt_fraction", self.dt_fraction, self.dt_fraction > 0.0)?;
        let v = &self.divergence;
        check("divergence.max_strain", v.max_strain, v.max_strain > 0.0)?;
        check(
            "divergence.max_step_travel",
            v.max_step_travel,
            v.max_step_travel > 0.0,
        )?;
        Ok(())
    }
}

/// The locomotion palette: a passive and an actuated silicone foam (paper §IV: open- and
/// closed-cell foam rubber), E = 300 kPa, ν = 0.35, ρ = 500 kg/m³ (a 3,500-voxel robot of 1 mm
/// voxels then weighs ~1.7 g, the paper's Table IV weight read in kg), static friction 1.0,
/// kinetic 0.3 (the paper's values).
pub fn foam_palette() -> Palette {
    let foam = |name: &str, actuated: bool, colour: [u8; 3]| {
        let mut m = Material::new(name, 3.0e5, 0.35);
        m.density = 500.0;
        m.static_friction = 1.0;
        m.kinetic_friction = 0.3;
        m.actuated = actuated;
        m.colour = colour;
        m
    };
    Palette(vec![
        foam("passive foam", false, [240, 240, 240]),
        foam("actuated foam", true, [240, 140, 40]),
    ])
}
