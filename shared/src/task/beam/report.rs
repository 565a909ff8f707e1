//! What a beam run reports: the Table III row with the paper's simulated error beside ours, the
//! profile against its target (CSV and plot), and the bounds an outcome from a peer must respect.

use std::path::Path;

use super::scene::{BeamMetrics, BeamScene};
use crate::report::{Block, PlotSpec, Series, line_plot};
use crate::task::Artefact;
use crate::task::error::{ImplausibleClaim, counts_fit, implausible};
use crate::voxel::GridDims;

fn percent(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.3} %"))
}

pub(super) fn summary(scene: &BeamScene, m: Option<&BeamMetrics>) -> serde_json::Value {
    serde_json::json!({
        "target": scene.target.label(),
        "best_rms_percent": m.map(|m| m.rms_percent),
        "paper_rms_percent": scene.target.paper_rms_percent(),
        "tip_deflection_m": m.map(|m| m.tip_deflection),
        "voxels": m.map(|m| m.voxels),
        "material_counts": m.map(|m| m.material_counts.clone()),
    })
}

/// Table III's columns for the best beam; a custom target has no paper column.
pub(super) fn table(scene: &BeamScene, m: Option<&BeamMetrics>, dims: GridDims) -> (String, Block) {
    let paper = scene.target.paper_rms_percent();
    let mut header = vec!["target", "RMS error (% of tip deflection)"];
    let mut row = vec![scene.target.label(), percent(m.map(|m| m.rms_percent))];
    if paper.is_some() {
        header.push("paper, simulated");
        row.push(percent(paper));
    }
    header.extend(["tip deflection", "voxels", "resolution"]);
    row.extend([
        m.map_or("-".into(), |m| format!("{:.4} mm", 1e3 * m.tip_deflection)),
        m.map_or("-".into(), |m| m.voxels.to_string()),
        dims.to_string(),
    ]);
    (
        "Shape-matching error (paper Table III)".into(),
        Block::Table {
            header: header.into_iter().map(String::from).collect(),
            rows: vec![row],
        },
    )
}

/// profile.csv and profile.png: the deflected top surface against the target.
pub(super) fn write_profile(dir: &Path, m: &BeamMetrics) -> std::io::Result<Vec<Artefact>> {
    let mut csv = String::from("t,simulated,target\n");
    for [t, w, f] in &m.profile {
        csv.push_str(&format!("{t},{w},{f}\n"));
    }
    std::fs::write(dir.join("profile.csv"), csv)?;
    let pick = |k: usize| m.profile.iter().map(|p| [p[0], p[k]]).collect();
    let series = [
        Series {
            label: "TARGET".into(),
            colour: [120, 120, 120],
            markers: false,
            points: pick(2),
        },
        Series {
            label: "SIMULATED".into(),
            colour: [214, 39, 40],
            markers: true,
            points: pick(1),
        },
    ];
    let spec = PlotSpec {
        title: format!("TOP SURFACE, RMS {:.3} %", m.rms_percent),
        x_label: "POSITION ALONG THE BEAM (CLAMP 0, TIP 1)".into(),
        y_label: "DEFLECTION / TIP DEFLECTION".into(),
        log_x: false,
        log_y: false,
    };
    let png = line_plot(&spec, &series)
        .to_png()
        .map_err(std::io::Error::other)?;
    std::fs::write(dir.join("profile.png"), png)?;
    Ok(vec![
        Artefact {
            path: "profile.png".into(),
            caption: Some("deflected top surface against the target".into()),
        },
        Artefact {
            path: "profile.csv".into(),
            caption: None,
        },
    ])
}

/// The bounds of a beam outcome at `dims`: a peer's report outside them was not produced by this
/// scene. Stations are the layers 1..ny−1 at t = y/(ny−1) plus the clamp at 0, in order; counts
/// fit the grid; the tip deflects downward; the fitness and RMS error are the ones the profile gives.
pub(super) fn check_metrics(
    scene: &BeamScene,
    fitness: f64,
    m: &BeamMetrics,
    dims: GridDims,
) -> Result<(), ImplausibleClaim> {
    counts_fit(m.voxels, &m.material_counts, scene.palette.len(), dims)?;
    if m.surface_voxels > dims.nx * dims.ny {
        return Err(implausible!(
            "surface_voxels = {} exceeds the {} columns",
            m.surface_voxels,
            dims.nx * dims.ny
        ));
    }
    if !(m.tip_deflection.is_finite() && m.tip_deflection > 0.0) {
        return Err(implausible!(
            "tip_deflection = {} is not a downward deflection",
            m.tip_deflection
        ));
    }
    if !(m.solver_residual.is_finite() && m.solver_residual >= 0.0) {
        return Err(implausible!(
            "solver_residual = {} is not a residual",
            m.solver_residual
        ));
    }
    let stations = &m.profile;
    if stations.len() < 2 || stations.len() > dims.ny {
        return Err(implausible!(
            "profile has {} stations, expected 2..={} at {dims}",
            stations.len(),
            dims.ny
        ));
    }
    if stations[0] != [0.0, 0.0, 0.0] {
        return Err(ImplausibleClaim(
            "profile must start at the clamp, [0, 0, 0]".into(),
        ));
    }
    let tip_y = (dims.ny - 1) as f64;
    let mut last = 0.0;
    let mut sum_sq = 0.0;
    for (i, &[t, w, target]) in stations.iter().enumerate().skip(1) {
        let layer = t * tip_y;
        if !(t > last && t <= 1.0 && (layer - layer.round()).abs() < 1e-9) {
            return Err(implausible!(
                "profile[{i}]: station t = {t} is not a layer after {last} in (0, 1]"
            ));
        }
        // A kept beam deflects between clamp and tip; a station's mean, normalized by the tip's,
        // is finite and bounded by what a 1000:1 palette can bend (any finite value is a
        // physically possible mean only within the section's rotation, so bound it loosely).
        if !(w.is_finite() && w.abs() <= 1e6) {
            return Err(implausible!(
                "profile[{i}]: deflection {w} is not a normalized deflection"
            ));
        }
        let expected = scene.target.deflection(t);
        if target.to_bits() != expected.to_bits() {
            return Err(implausible!(
                "profile[{i}]: target {target} differs from this scene's {expected} at t = {t}"
            ));
        }
        sum_sq += (w - target).powi(2);
        last = t;
    }
    if (last - 1.0).abs() > 0.0 {
        return Err(ImplausibleClaim(
            "profile must end at the tip, t = 1".into(),
        ));
    }
    // The evaluation sums the same squares in the same order, so its fitness is this to the bit.
    if fitness.to_bits() != (-sum_sq).to_bits() {
        return Err(implausible!(
            "fitness {fitness} differs from the profile's {}",
            -sum_sq
        ));
    }
    let rms = 100.0 * (sum_sq / (stations.len() - 1) as f64).sqrt();
    if !(rms.is_finite() && (rms - m.rms_percent).abs() <= 1e-9 * rms.max(1.0)) {
        return Err(implausible!(
            "rms_percent = {} differs from the profile's {rms}",
            m.rms_percent
        ));
    }
    Ok(())
}
