//! Every numeric setting of the static solver, in one serde-able struct with named presets.

use serde::{Deserialize, Serialize};

use super::error::{Result, StaticsError};

/// Which linear solver to use for `K u = f`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverMethod {
    /// Direct below [`StaticSolverParams::auto_direct_max_dof`] free unknowns, PCG above.
    Auto,
    /// faer's sparse Cholesky (AMD ordering, supernodal): exact to round-off, memory and time grow
    /// with the fill of the factor (fast for small grids, minutes for 10⁵–10⁶ unknowns).
    Direct,
    /// Preconditioned conjugate gradients with [`StaticSolverParams::preconditioner`].
    Pcg,
}

/// Preconditioner of the conjugate-gradient method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preconditioner {
    /// Smoothed-aggregation algebraic multigrid V-cycle (see [`MultigridParams`]): iterations
    /// nearly independent of size and stiffness contrast; costs a setup of a few matrix products.
    Multigrid,
    /// Inverse of each node's 6×6 diagonal block: no setup, but iterations grow with the grid
    /// size and the stiffness contrast (thousands on a 1000:1 beam).
    BlockJacobi,
}

/// Settings of the smoothed-aggregation multigrid preconditioner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MultigridParams {
    /// Stop coarsening when a level has at most this many nodes (6 unknowns each); that level is
    /// factored directly. Default 200: a dense-ish factor of ≤ 1200 unknowns costs milliseconds,
    /// while a larger value adds factor time and a smaller one adds levels.
    pub coarse_max_nodes: usize,
    /// Most levels, fine one included (default 12; a 2×2×2 aggregation divides nodes by ~8 per
    /// level, so this is never the binding limit on feasible grids).
    pub max_levels: usize,
    /// Prolongator smoothing factor ω·λ_max(D⁻¹A) (default 4/3, the classical choice that
    /// minimises the energy of the smoothed basis; 0 gives unsmoothed aggregation, cheaper coarse
    /// operators but many more iterations).
    pub prolongator_damping: f64,
    /// Power iterations estimating λ_max(D⁻¹A) for the prolongator smoothing (default 12; the
    /// estimate only needs ~10 % accuracy).
    pub power_iterations: usize,
    /// Symmetric block Gauss–Seidel sweeps before and after the coarse correction (default 1; one
    /// sweep is a forward then a backward pass, which keeps the V-cycle symmetric for CG).
    pub smoothing_sweeps: usize,
}

impl Default for MultigridParams {
    fn default() -> Self {
        Self {
            coarse_max_nodes: 200,
            max_levels: 12,
            prolongator_damping: 4.0 / 3.0,
            power_iterations: 12,
            smoothing_sweeps: 1,
        }
    }
}

/// Settings of [`solve`](super::solve).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StaticSolverParams {
    /// Solver choice (default [`SolverMethod::Auto`]).
    pub method: SolverMethod,
    /// Target true relative residual ‖K u − f‖ / ‖f‖ in SI units (default 1e-9). Tighter costs a
    /// few PCG iterations per decade; looser makes the beam profile noisy at 1000:1 contrast.
    pub tolerance: f64,
    /// Most PCG iterations before [`StaticsError::NotConverged`] (default 2000; multigrid needs
    /// tens, block Jacobi thousands).
    pub max_iterations: usize,
    /// `Auto` solves directly up to this many free unknowns (6 per free node), by PCG above
    /// (default 6000, from the measured crossover in `docs/explanation/physics.md`).
    pub auto_direct_max_dof: usize,
    /// PCG preconditioner (default multigrid).
    pub preconditioner: Preconditioner,
    /// Multigrid settings.
    pub multigrid: MultigridParams,
}

impl Default for StaticSolverParams {
    fn default() -> Self {
        Self {
            method: SolverMethod::Auto,
            tolerance: 1e-9,
            max_iterations: 2000,
            auto_direct_max_dof: 6000,
            preconditioner: Preconditioner::Multigrid,
            multigrid: MultigridParams::default(),
        }
    }
}

impl StaticSolverParams {
    /// Always the sparse Cholesky: the reference for tests.
    pub fn direct() -> Self {
        Self {
            method: SolverMethod::Direct,
            ..Self::default()
        }
    }

    /// Always multigrid-preconditioned CG.
    pub fn multigrid_pcg() -> Self {
        Self {
            method: SolverMethod::Pcg,
            ..Self::default()
        }
    }

    /// Always block-Jacobi-preconditioned CG (a baseline for comparisons).
    pub fn block_jacobi_pcg() -> Self {
        Self {
            method: SolverMethod::Pcg,
            preconditioner: Preconditioner::BlockJacobi,
            max_iterations: 50_000,
            ..Self::default()
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        let check = |field: &'static str, value: f64, ok: bool| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(StaticsError::InvalidParameter { field, value })
            }
        };
        check(
            "tolerance",
            self.tolerance,
            self.tolerance > 0.0 && self.tolerance < 1.0,
        )?;
        check(
            "max_iterations",
            self.max_iterations as f64,
            self.max_iterations > 0,
        )?;
        let mg = &self.multigrid;
        check(
            "multigrid.coarse_max_nodes",
            mg.coarse_max_nodes as f64,
            mg.coarse_max_nodes > 0,
        )?;
        check(
            "multigrid.max_levels",
            mg.max_levels as f64,
            mg.max_levels > 0,
        )?;
        check(
            "multigrid.prolongator_damping",
            mg.prolongator_damping,
            (0.0..2.0).contains(&mg.prolongator_damping),
        )?;
        check(
            "multigrid.power_iterations",
            mg.power_iterations as f64,
            mg.power_iterations > 0,
        )?;
        check(
            "multigrid.smoothing_sweeps",
            mg.smoothing_sweeps as f64,
            mg.smoothing_sweeps > 0,
        )?;
        Ok(())
    }
}
