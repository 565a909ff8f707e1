//! What a stiffness run reports, and the bounds an outcome from a peer must respect.

use super::evaluate::{fitness, reference_deflection};
use super::scene::{StiffnessMetrics, StiffnessScene};
use crate::report::Block;
use crate::task::error::{ImplausibleClaim, counts_fit, implausible};
use crate::voxel::GridDims;

pub(super) fn summary(scene: &StiffnessScene, m: Option<&StiffnessMetrics>) -> serde_json::Value {
    serde_json::json!({
        "task": "stiffness",
        "max_hard_fraction": scene.max_hard_fraction,
        "relative_stiffness": m.map(|m| m.relative_stiffness),
        "tip_deflection_m": m.map(|m| m.tip_deflection),
        "hard_fraction": m.map(|m| m.hard_fraction),
        "within_budget": m.map(|m| m.within_budget),
        "flange_efficiency": m.map(|m| m.flange_efficiency),
        "voxels": m.map(|m| m.voxels),
        "material_counts": m.map(|m| m.material_counts.clone()),
    })
}

pub(super) fn table(
    scene: &StiffnessScene,
    m: Option<&StiffnessMetrics>,
    dims: GridDims,
) -> (String, Block) {
    let num = |v: Option<f64>, digits: usize, unit: &str| {
        v.map_or("-".to_string(), |v| format!("{v:.digits$}{unit}"))
    };
    let row = |name: &str, value: String| vec![name.to_string(), value];
    (
        "Stiffness for a budget of hard material".into(),
        Block::Table {
            header: ["", "this run"].map(String::from).to_vec(),
            rows: vec![
                row(
                    "tip stiffness / all-hard workspace's (beam theory)",
                    num(m.map(|m| m.relative_stiffness), 4, ""),
                ),
                row(
                    "tip deflection",
                    num(m.map(|m| 1e3 * m.tip_deflection), 5, " mm"),
                ),
                row(
                    "hard fraction of the workspace",
                    format!(
                        "{} (budget {:.1} %)",
                        num(m.map(|m| 100.0 * m.hard_fraction), 1, " %"),
                        100.0 * scene.max_hard_fraction
                    ),
                ),
                row(
                    "flange efficiency (1 = I-beam layout of the same hard area)",
                    num(m.map(|m| m.flange_efficiency), 3, ""),
                ),
                row(
                    "voxels",
                    m.map_or("-".into(), |m| format!("{} at {dims}", m.voxels)),
                ),
            ],
        },
    )
}

/// The bounds of a stiffness outcome at `dims`: counts fit the grid, the hard fraction, budget
/// flag, relative stiffness and fitness are the ones the counts and the tip deflection give.
pub(super) fn check_metrics(
    scene: &StiffnessScene,
    fitness_claimed: f64,
    m: &StiffnessMetrics,
    dims: GridDims,
) -> Result<(), ImplausibleClaim> {
    counts_fit(m.voxels, &m.material_counts, scene.palette.len(), dims)?;
    if !(m.tip_deflection.is_finite() && m.tip_deflection > 0.0) {
        return Err(implausible!(
            "tip_deflection = {} is not a downward deflection",
            m.tip_deflection
        ));
    }
    let hard = m.material_counts[usize::from(scene.hard_material)];
    let expected = StiffnessMetrics {
        relative_stiffness: reference_deflection(scene, dims) / m.tip_deflection,
        hard_fraction: hard as f64 / dims.cell_count() as f64,
        within_budget: hard as f64 / dims.cell_count() as f64 <= scene.max_hard_fraction,
        ..m.clone()
    };
    if expected != *m {
        return Err(implausible!(
            "relative_stiffness, hard_fraction or within_budget differ from the counts' {:?}",
            (
                expected.relative_stiffness,
                expected.hard_fraction,
                expected.within_budget
            )
        ));
    }
    if !(m.flange_efficiency.is_finite() && m.flange_efficiency >= 0.0) {
        return Err(implausible!(
            "flange_efficiency = {} is not a ratio",
            m.flange_efficiency
        ));
    }
    if fitness_claimed.to_bits() != fitness(m, scene).to_bits() {
        return Err(implausible!(
            "fitness {fitness_claimed} differs from the metrics' {}",
            fitness(m, scene)
        ));
    }
    Ok(())
}
