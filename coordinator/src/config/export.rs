//! `[export]`: what a run writes beyond the fabrication files (the voxel-print slice stack) and
//! the check of its best design at twice its final resolution.

use amorph::export::PrintPitch;
use serde::{Deserialize, Serialize};

/// End-of-run exports beyond the fabrication files, and the finer check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExportSection {
    /// Write `exports/slices/`: one PNG per printed layer sampled from the genome's field.
    pub print: bool,
    /// The printer's dots per inch along x and y (default 600 × 300, a J750-class PolyJet).
    pub print_dpi: [f64; 2],
    /// The printer's layer thickness in millimetres (default 0.027).
    pub print_layer_mm: f64,
    /// Re-evaluate the best design at twice the final resolution per axis and report the change.
    pub finer_check: bool,
}

impl Default for ExportSection {
    fn default() -> Self {
        let pitch = PrintPitch::default();
        ExportSection {
            print: true,
            print_dpi: [pitch.dpi_x, pitch.dpi_y],
            print_layer_mm: pitch.layer_mm,
            finer_check: true,
        }
    }
}

impl ExportSection {
    pub fn pitch(&self) -> PrintPitch {
        PrintPitch {
            dpi_x: self.print_dpi[0],
            dpi_y: self.print_dpi[1],
            layer_mm: self.print_layer_mm,
        }
    }

    /// Names the bad key, e.g. `export.print_dpi[0] = 0: …`.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        for (i, &dpi) in self.print_dpi.iter().enumerate() {
            if !positive(dpi) {
                return Err(format!(
                    "export.print_dpi[{i}] = {dpi} must be a positive number of dots per inch"
                ));
            }
        }
        if !positive(self.print_layer_mm) {
            return Err(format!(
                "export.print_layer_mm = {} must be a positive layer thickness in mm",
                self.print_layer_mm
            ));
        }
        Ok(())
    }
}
