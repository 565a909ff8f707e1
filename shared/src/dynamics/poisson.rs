//! Lateral Poisson coupling: a voxel stretched along one axis contracts along the others by ν.
//!
//! A lattice of independent axial links has an effective Poisson's ratio of 0. Isotropic linear
//! elasticity per voxel, W/V = ½M Σᵢ εᵢ² + λ Σᵢ<ⱼ εᵢεⱼ (M = λ + 2μ, the P-wave modulus), is split
//! in two so that it stays an exact potential, and so conserves energy undamped:
//! - the diagonal ½M εᵢ² lives in each link: its axial stiffness is M·A/L instead of E·A/L
//!   (`apply_to_links`), so alternating strain patterns still cost energy (no hourglass modes);
//! - the coupling λ εᵢεⱼ lives in each voxel, on its mean strain per axis ēᵢ (the mean of the
//!   strains |r|/L₀ − 1 of its two links along i): W_c = Σ_v Σᵢ<ⱼ V λ ēᵢ ēⱼ, over the pairs of
//!   axes along which the voxel has links on both sides (each link's strain weighted by its own
//!   modulus where materials differ, see `weighted_strains`).
//!
//! The forces are the exact gradient of W_c: each link gets a central force (∂W_c/∂ε_l)/L₀ along
//! its current direction, ∂W_c/∂ε_l = Σ over its two voxels of (∂W_c/∂ēᵢ)/2.
//!
//! Only *interior* directions couple: a voxel with a link on one side only along an axis is at a
//! free surface there, and the one link measures the mean strain between it and its neighbour,
//! which in bending is zero where the true lateral strain is ±νε: coupling it would lock thin
//! sections (a first version that did made the 2×2×20 cantilever 12 % too stiff). So each voxel
//! is condensed to the axes along which it has two links: three gives the full 3-D constants,
//! two plane stress (M = E/(1−ν²), λ = Eν/(1−ν²)), fewer uniaxial stress (M = E, no coupling).
//! Bodies one or two voxels thick are therefore unchanged by the coupling, and a bulk body gets E
//! and ν in its interior, its surface layer contracting less: across a pulled n×n bar ν reads
//! −26 %, −13 %, −8 % and −6 % low at n = 4, 6, 8 and 12, between its inner columns +9 %, +8 %,
//! +6 % and +3 % high (test `dynamics_poisson`). The price is the
//! stiffer P-wave modulus of a confined solid: at ν = 0.35 an interior link is 1.60× stiffer
//! axially, so the automatic time step (from the stiffest link) is 1/√1.60 = 0.79× as long.

use super::link::LinkStep;
use super::state::{Links, Voxels};
use crate::material::link_youngs_modulus;

/// The per-voxel constants and scratch of the coupling pass.
#[derive(Clone, Debug, Default)]
pub struct PoissonCoupling {
    /// Per voxel and axis, ½√(λ/M) of the voxel's condensed constants on an interior axis, 0 on
    /// the others (which do not couple).
    scale: Vec<[f64; 3]>,
    /// Per link, √M of its axial modulus (Pa^½).
    root_modulus: Vec<f64>,
    /// Voxel volume s³.
    volume: f64,
    /// Scratch per voxel and axis: first the weighted strains ẽᵢ, then ∂W_c/∂ẽᵢ times `scale`.
    scratch: Vec<[f64; 3]>,
    /// Scratch per link: its length |x_b − x_a| this step, measured once for both loops.
    lengths: Vec<f64>,
}

/// Condensed elastic constants (M, λ) of a voxel of modulus `e` and Poisson's ratio `nu` with
/// `axes` interior axes (links on both sides): the stress along the other axes is zero.
fn condensed(e: f64, nu: f64, axes: usize) -> (f64, f64) {
    match axes {
        3 => {
            let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
            (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)), lambda)
        }
        2 => (e / (1.0 - nu * nu), e * nu / (1.0 - nu * nu)),
        _ => (e, 0.0),
    }
}

impl PoissonCoupling {
    /// Builds the coupling and stiffens every link's axial term to the condensed modulus M of its
    /// voxels (the harmonic mean of the two ends, like E for a mixed link); `voxel_size` is s.
    pub fn apply_to_links(voxels: &Voxels, links: &mut Links, voxel_size: f64) -> Self {
        let n = voxels.len();
        let youngs: Vec<f64> = voxels.stiffness.iter().map(|k| k / voxel_size).collect();
        let nu = &voxels.poisson_ratio;
        let mut count = vec![[0u8; 3]; n];
        for k in 0..links.len() {
            let axis = usize::from(links.axis[k]);
            count[links.a[k] as usize][axis] += 1;
            count[links.b[k] as usize][axis] += 1;
        }
        let mut modulus = vec![0.0; n];
        let mut scale = vec![[0.0; 3]; n];
        for i in 0..n {
            let interior = count[i].map(|c| c == 2);
            let axes = interior.iter().filter(|&&x| x).count();
            let (m, lambda) = condensed(youngs[i], nu[i], axes);
            modulus[i] = m;
            if axes >= 2 {
                let root = 0.5 * (lambda / m).sqrt();
                scale[i] = interior.map(|x| if x { root } else { 0.0 });
            }
        }
        let mut root_modulus = Vec::with_capacity(links.len());
        for k in 0..links.len() {
            let (a, b) = (links.a[k] as usize, links.b[k] as usize);
            let link_modulus = link_youngs_modulus(modulus[a], modulus[b]);
            links.axial[k] *= link_modulus / link_youngs_modulus(youngs[a], youngs[b]);
            root_modulus.push(link_modulus.sqrt());
        }
        Self {
            scale,
            root_modulus,
            volume: voxel_size.powi(3),
            scratch: vec![[0.0; 3]; n],
            lengths: vec![0.0; links.len()],
        }
    }

    /// Whether any voxel couples at all (every ν = 0, or a body at most two voxels thick, needs
    /// no pass).
    pub fn is_active(&self) -> bool {
        self.scale.iter().flatten().any(|&w| w != 0.0)
    }

    /// Each voxel's weighted mean strain per axis, ẽᵢ = Σ_l ½√(M_l λ/M) ε_l over its links along
    /// i, into `strain`: with one material it is √λ ēᵢ, and weighting each link by its own
    /// modulus keeps W_c below the links' own energy where a stiff voxel meets a soft one (with
    /// a voxel's λ on a soft link's strain the sum is not positive definite: a 1e4 stiffness
    /// jump diverged within 400 steps). Strains are against the links' rest lengths at `step`;
    /// each link's length goes into `lengths`.
    fn weighted_strains(
        &self,
        strain: &mut [[f64; 3]],
        lengths: &mut [f64],
        links: &Links,
        voxels: &Voxels,
        step: LinkStep,
    ) {
        let stretch = step.actuation_factor - 1.0;
        strain.fill([0.0; 3]);
        for (k, length_k) in lengths.iter_mut().enumerate().take(links.len()) {
            let (a, b) = (links.a[k] as usize, links.b[k] as usize);
            let axis = usize::from(links.axis[k]);
            let rest = links.rest_length(k, step.voxel_size, stretch);
            let length = (voxels.position[b] - voxels.position[a]).norm();
            *length_k = length;
            let e = (length / rest - 1.0) * self.root_modulus[k];
            strain[a][axis] += e * self.scale[a][axis];
            strain[b][axis] += e * self.scale[b][axis];
        }
    }

    /// Adds the coupling forces to the voxels, with the links' rest lengths at `step` (the
    /// actuated ones while actuating).
    pub fn pass(&mut self, links: &Links, voxels: &mut Voxels, step: LinkStep) {
        let stretch = step.actuation_factor - 1.0;
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut lengths = std::mem::take(&mut self.lengths);
        self.weighted_strains(&mut scratch, &mut lengths, links, voxels, step);
        for (e, scale) in scratch.iter_mut().zip(&self.scale) {
            // ∂W_c/∂ẽᵢ = V Σ_{j≠i} ẽⱼ, times the link-independent part of ∂ẽᵢ/∂ε_l.
            let [ex, ey, ez] = *e;
            let v = self.volume;
            *e = [
                v * (ey + ez) * scale[0],
                v * (ex + ez) * scale[1],
                v * (ex + ey) * scale[2],
            ];
        }
        for (k, &length) in lengths.iter().enumerate().take(links.len()) {
            let (a, b) = (links.a[k] as usize, links.b[k] as usize);
            let axis = usize::from(links.axis[k]);
            let generalised = (scratch[a][axis] + scratch[b][axis]) * self.root_modulus[k];
            let r = voxels.position[b] - voxels.position[a];
            let rest = links.rest_length(k, step.voxel_size, stretch);
            // ∂ε/∂x_b = r/(|r| L₀): the force on b is −(∂W_c/∂ε) times that.
            let f = r * (generalised / (length * rest));
            voxels.force[a] += f;
            voxels.force[b] -= f;
        }
        self.scratch = scratch;
        self.lengths = lengths;
    }

    /// The coupling energy W_c = V Σ_v Σᵢ<ⱼ ẽᵢ ẽⱼ (J) of the current state.
    pub fn energy(&self, links: &Links, voxels: &Voxels, step: LinkStep) -> f64 {
        let mut strain = vec![[0.0; 3]; self.scale.len()];
        let mut lengths = vec![0.0; links.len()];
        self.weighted_strains(&mut strain, &mut lengths, links, voxels, step);
        self.volume
            * strain
                .iter()
                .map(|e| e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
                .sum::<f64>()
    }
}

#[cfg(test)]
mod tests;
