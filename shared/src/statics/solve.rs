//! `solve`: checks a load case, assembles the reduced system and runs the chosen solver.

use serde::{Deserialize, Serialize};

use super::amg::{Multigrid, MultigridPreconditioner};
use super::bsr::two_sum;
use super::direct::DirectFactor;
use super::error::{Result, StaticsError};
use super::model::StaticModel;
use super::params::{Preconditioner, SolverMethod, StaticSolverParams};
use super::pcg::{BlockJacobi, Precondition, pcg};
use super::system::ReducedSystem;

/// Supports and loads of one static analysis.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StaticLoadCase {
    /// Nodes clamped in all six DOF.
    pub fixed_nodes: Vec<usize>,
    /// Per loaded node: force (N) along x, y, z and moment (N·m) about x, y, z. Loads on fixed
    /// nodes go straight into the support and are ignored; repeated nodes add up.
    pub loads: Vec<(usize, [f64; 6])>,
}

impl StaticLoadCase {
    /// The cantilever the static tasks load: the nodes of the `y = 0` layer clamped, a total force
    /// `tip_load` (N, along −z) spread evenly over the nodes of the last layer, each layer's nodes
    /// in (z, x) order.
    pub fn cantilever(model: &StaticModel, tip_load: f64) -> Self {
        let dims = model.dims();
        let layer = |y: usize| {
            (0..dims.nz)
                .flat_map(move |z| (0..dims.nx).map(move |x| dims.index(x, y, z)))
                .filter_map(|cell| model.node_of_cell(cell))
        };
        let tip: Vec<usize> = layer(dims.ny - 1).collect();
        let force = -tip_load / tip.len() as f64;
        Self {
            fixed_nodes: layer(0).collect(),
            loads: tip
                .iter()
                .map(|&n| (n, [0.0, 0.0, force, 0.0, 0.0, 0.0]))
                .collect(),
        }
    }
}

/// The solver that produced a solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolveMethodUsed {
    /// Nothing to solve: every node is fixed or every load is zero.
    Trivial,
    Direct,
    PcgBlockJacobi,
    PcgMultigrid,
}

/// How a solution was obtained. Deliberately without wall times, so a solution is a
/// bit-reproducible function of its inputs; time the solver in the benches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolveDiagnostics {
    pub method: SolveMethodUsed,
    /// PCG iterations (0 for a direct solve).
    pub iterations: usize,
    /// True relative residual ‖K u − f‖ / ‖f‖ in SI units, recomputed after the solve
    /// (0 when f = 0).
    pub relative_residual: f64,
    /// Free unknowns (6 per free node).
    pub unknowns: usize,
    /// Multigrid levels, fine one included (0 without multigrid).
    pub levels: usize,
}

/// Displacements of every node of the model, fixed ones included (zero).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticSolution {
    /// Per node: displacement (m) along x, y, z and rotation (rad) about x, y, z.
    pub displacements: Vec<[f64; 6]>,
    pub diagnostics: SolveDiagnostics,
}

/// Marks the fixed nodes, checking them against the model.
fn fixed_flags(model: &StaticModel, fixed_nodes: &[usize]) -> Result<Vec<bool>> {
    let node_count = model.node_count();
    if fixed_nodes.is_empty() {
        return Err(StaticsError::NoFixedNode);
    }
    let mut fixed = vec![false; node_count];
    for &node in fixed_nodes {
        if node >= node_count {
            return Err(StaticsError::NodeOutOfRange {
                field: "fixed_nodes",
                node,
                node_count,
            });
        }
        fixed[node] = true;
    }
    Ok(fixed)
}

/// Checks that every load is on a node of the model and finite.
fn check_loads(loads: &[(usize, [f64; 6])], node_count: usize) -> Result<()> {
    for &(node, load) in loads {
        if node >= node_count {
            return Err(StaticsError::NodeOutOfRange {
                field: "loads",
                node,
                node_count,
            });
        }
        if let Some(component) = load.iter().position(|v| !v.is_finite()) {
            return Err(StaticsError::NonFiniteLoad {
                node,
                component,
                value: load[component],
            });
        }
    }
    Ok(())
}

/// Every node must reach a fixed node through links, or K is singular (a floating part).
fn check_supported(model: &StaticModel, fixed: &[bool]) -> Result<()> {
    let mut reached = fixed.to_vec();
    let mut stack: Vec<usize> = (0..fixed.len()).filter(|&n| fixed[n]).collect();
    while let Some(node) = stack.pop() {
        for &link in model.node_links(node) {
            let [i, j] = model.link_nodes(link as usize);
            let other = if i == node { j } else { i };
            if !reached[other] {
                reached[other] = true;
                stack.push(other);
            }
        }
    }
    let count = reached.iter().filter(|&&r| !r).count();
    match reached.iter().position(|&r| !r) {
        Some(first) => Err(StaticsError::Unconnected { count, first }),
        None => Ok(()),
    }
}

/// How the prepared solver will solve.
enum Backend {
    /// No free unknowns.
    Empty,
    Direct(DirectFactor),
    Pcg {
        preconditioner: Box<dyn Precondition>,
        used: SolveMethodUsed,
    },
}

impl std::fmt::Debug for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Empty => f.write_str("Empty"),
            Self::Direct(_) => f.write_str("Direct"),
            Self::Pcg { used, .. } => write!(f, "Pcg({used:?})"),
        }
    }
}

/// Most refinement steps after a direct solve before giving up on the tolerance.
const MAX_REFINEMENTS: usize = 8;

/// A solver prepared for one model and one set of supports: the reduced stiffness is assembled and
/// factored (direct) or its multigrid hierarchy built (PCG) once, then any number of load vectors
/// are solved. [`solve`] is this for a single load case.
#[derive(Debug)]
pub struct StaticSolver {
    system: ReducedSystem,
    reduced_of_node: Vec<u32>,
    backend: Backend,
    levels: usize,
    tolerance: f64,
    max_iterations: usize,
}

impl StaticSolver {
    /// Checks the supports, assembles the free nodes' stiffness and sets up the chosen method.
    pub fn new(
        model: &StaticModel,
        fixed_nodes: &[usize],
        params: &StaticSolverParams,
    ) -> Result<Self> {
        params.validate()?;
        let fixed = fixed_flags(model, fixed_nodes)?;
        check_supported(model, &fixed)?;
        let system = ReducedSystem::assemble(model, &fixed);
        let mut reduced_of_node = vec![u32::MAX; model.node_count()];
        for (r, &node) in system.free_nodes.iter().enumerate() {
            reduced_of_node[node as usize] = r as u32;
        }
        let dof = system.matrix.dof();
        let method = match params.method {
            SolverMethod::Auto if dof <= params.auto_direct_max_dof => SolverMethod::Direct,
            SolverMethod::Auto => SolverMethod::Pcg,
            m => m,
        };
        let mut levels = 0;
        let backend = if dof == 0 {
            Backend::Empty
        } else if method == SolverMethod::Pcg {
            let (preconditioner, used): (Box<dyn Precondition>, _) = match params.preconditioner {
                Preconditioner::BlockJacobi => (
                    Box::new(BlockJacobi::new(&system.matrix)?),
                    SolveMethodUsed::PcgBlockJacobi,
                ),
                Preconditioner::Multigrid => {
                    let coords: Vec<[u32; 3]> = system
                        .free_nodes
                        .iter()
                        .map(|&n| model.node_coords(n as usize).map(|c| c as u32))
                        .collect();
                    let multigrid = Multigrid::new(&system.matrix, &coords, &params.multigrid)?;
                    levels = multigrid.level_count();
                    (
                        Box::new(MultigridPreconditioner {
                            multigrid,
                            sweeps: params.multigrid.smoothing_sweeps,
                        }),
                        SolveMethodUsed::PcgMultigrid,
                    )
                }
            };
            Backend::Pcg {
                preconditioner,
                used,
            }
        } else {
            Backend::Direct(DirectFactor::new(&system.matrix)?)
        };
        Ok(Self {
            system,
            reduced_of_node,
            backend,
            levels,
            tolerance: params.tolerance,
            max_iterations: params.max_iterations,
        })
    }

    /// Free unknowns (6 per free node).
    pub fn unknowns(&self) -> usize {
        self.system.matrix.dof()
    }

    /// Solves for one set of nodal loads (force N, moment N·m per node; loads on fixed nodes are
    /// ignored, repeated nodes add up).
    pub fn solve(&mut self, loads: &[(usize, [f64; 6])]) -> Result<StaticSolution> {
        let node_count = self.reduced_of_node.len();
        check_loads(loads, node_count)?;
        let s = self.system.scale;
        // f̃ = (F, M / s)
        let mut rhs = vec![0.0; self.system.matrix.dof()];
        for &(node, load) in loads {
            let r = self.reduced_of_node[node];
            if r == u32::MAX {
                continue;
            }
            let f = &mut rhs[6 * r as usize..6 * r as usize + 6];
            for (k, (fk, lk)) in f.iter_mut().zip(load).enumerate() {
                *fk += if k < 3 { lk } else { lk / s };
            }
        }
        let mut x = vec![0.0; rhs.len()];
        let mut diagnostics = SolveDiagnostics {
            method: SolveMethodUsed::Trivial,
            iterations: 0,
            relative_residual: 0.0,
            unknowns: rhs.len(),
            levels: self.levels,
        };
        if rhs.iter().any(|&v| v != 0.0) {
            let (method, iterations, relative) = self.refine(&rhs, &mut x)?;
            diagnostics.method = method;
            diagnostics.iterations = iterations;
            diagnostics.relative_residual = relative;
        }
        let mut displacements = vec![[0.0; 6]; node_count];
        for (r, &node) in self.system.free_nodes.iter().enumerate() {
            let xr = &x[6 * r..6 * r + 6];
            // θ = θ̃ / s
            displacements[node as usize] =
                std::array::from_fn(|k| if k < 3 { xr[k] } else { xr[k] / s });
        }
        Ok(StaticSolution {
            displacements,
            diagnostics,
        })
    }

    /// Mixed-precision iterative refinement around the chosen backend. The solution is carried as
    /// x + x_lo and its residual computed with compensated arithmetic, so the refinement converges
    /// below the cancellation floor of a plain double residual (~1e-7 of ‖f‖ at 1e6:1 contrast,
    /// where ‖K‖‖u‖/‖f‖ reaches 1e9). Each correction is solved only as accurately as the next
    /// step needs: the direct factor exactly, PCG to tolerance / current residual. Returns the
    /// method, the iterations (refinement steps for direct, CG iterations for PCG) and the true
    /// relative residual.
    fn refine(&mut self, rhs: &[f64], x: &mut [f64]) -> Result<(SolveMethodUsed, usize, f64)> {
        let norm_f = self.system.si_force_norm(rhs);
        let mut x_lo = vec![0.0; rhs.len()];
        let mut correction = vec![0.0; rhs.len()];
        let mut residual = rhs.to_vec();
        let mut relative = 1.0;
        let mut iterations = 0;
        let mut method = SolveMethodUsed::Trivial;
        for step in 0..=MAX_REFINEMENTS {
            let inner_tolerance = (self.tolerance / relative).min(0.1);
            match &mut self.backend {
                Backend::Empty => return Ok((method, iterations, 0.0)),
                Backend::Direct(factor) => {
                    correction.copy_from_slice(&residual);
                    factor.solve_in_place(&mut correction);
                    method = SolveMethodUsed::Direct;
                    iterations = step;
                }
                Backend::Pcg {
                    preconditioner,
                    used,
                } => {
                    method = *used;
                    let budget = self.max_iterations - iterations;
                    let report = pcg(
                        &self.system,
                        &residual,
                        preconditioner.as_mut(),
                        inner_tolerance,
                        budget,
                        &mut correction,
                    );
                    match report {
                        Ok(used) => iterations += used,
                        Err(used) => {
                            iterations += used;
                            relative = self.true_residual(rhs, x, &x_lo, &mut residual, norm_f);
                            return Err(StaticsError::NotConverged {
                                iterations,
                                residual: relative,
                                tolerance: self.tolerance,
                            });
                        }
                    }
                }
            }
            for ((hi, lo), d) in x.iter_mut().zip(&mut x_lo).zip(&correction) {
                (*hi, *lo) = two_sum(*hi, *lo + d);
            }
            relative = self.true_residual(rhs, x, &x_lo, &mut residual, norm_f);
            if relative.is_infinite() {
                break;
            }
            if relative <= self.tolerance {
                // The rounded sum is the answer; what it drops is below double resolution.
                x.iter_mut().zip(&x_lo).for_each(|(hi, lo)| *hi += lo);
                return Ok((method, iterations, relative));
            }
        }
        Err(StaticsError::NotConverged {
            iterations,
            residual: relative,
            tolerance: self.tolerance,
        })
    }

    /// The compensated true residual f − K (x + x_lo) into `residual`, its SI norm relative to
    /// ‖f‖ (infinite when the state is not finite).
    fn true_residual(
        &self,
        rhs: &[f64],
        x: &[f64],
        x_lo: &[f64],
        residual: &mut [f64],
        norm_f: f64,
    ) -> f64 {
        self.system
            .matrix
            .residual_compensated(rhs, x, x_lo, residual);
        let relative = self.system.si_force_norm(residual) / norm_f;
        if relative.is_finite() {
            relative
        } else {
            f64::INFINITY
        }
    }
}

/// Solves K u = f for one load case. Fails with a typed error, never a panic, for an
/// unsupported or floating design, bad input, or a solver that does not reach the tolerance.
pub fn solve(
    model: &StaticModel,
    case: &StaticLoadCase,
    params: &StaticSolverParams,
) -> Result<StaticSolution> {
    check_loads(&case.loads, model.node_count())?;
    StaticSolver::new(model, &case.fixed_nodes, params)?.solve(&case.loads)
}
