//! Voxel-print slice stacks: one image per printed layer, one colour per material, for PolyJet
//! printers that take a bitmap per layer (the "voxel print" workflow of GrabCAD Print and of
//! material-jetting research tools).
//!
//! A voxel design is a coarse sampling of the genome's continuous density field. A printer's
//! droplets are about 40 × 85 × 27 µm, so instead of scaling voxels up into blocks every droplet
//! samples the field itself, with the voxelization's own rule (total density above the threshold,
//! densest material): the print is as smooth as the genome, and sampled at the voxel centres it is
//! exactly the voxel design.
//!
//! Like the voxel design, the print keeps only what the task keeps (a beam's clamped part, a
//! robot's largest body): a droplet counts only in a kept voxel, or in an empty voxel next to one
//! (where the smooth surface may bulge past the voxel centres), never in a voxel of a part the task
//! discarded.

use std::path::{Path, PathBuf};

use crate::genome::Genome;
use crate::material::{MaterialId, Palette};
use crate::task::Scene;
use crate::voxel::{GridDims, LayerSampler, VoxelGrid, material_at, voxelize};

/// Millimetres per inch, for pitches given in dots per inch.
const MM_PER_INCH: f64 = 25.4;

/// Colour of a droplet position with no material: fully transparent, so only material pixels
/// carry colour.
pub const VOID_RGBA: [u8; 4] = [0, 0, 0, 0];

/// The printer's addressable grid. Defaults are a Stratasys J750-class PolyJet printer: 600 dpi
/// along x, 300 dpi along y, 27 µm layers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrintPitch {
    pub dpi_x: f64,
    pub dpi_y: f64,
    pub layer_mm: f64,
}

impl Default for PrintPitch {
    fn default() -> Self {
        PrintPitch {
            dpi_x: 600.0,
            dpi_y: 300.0,
            layer_mm: 0.027,
        }
    }
}

impl PrintPitch {
    /// Droplet spacing along x, y and z in millimetres.
    pub fn pitch_mm(&self) -> [f64; 3] {
        [
            MM_PER_INCH / self.dpi_x,
            MM_PER_INCH / self.dpi_y,
            self.layer_mm,
        ]
    }

    /// Refuses a pitch no printer has, naming the field.
    pub fn validate(&self) -> Result<(), String> {
        for (name, value) in [
            ("dpi_x", self.dpi_x),
            ("dpi_y", self.dpi_y),
            ("layer_mm", self.layer_mm),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(format!("print pitch: {name} must be positive, got {value}"));
            }
        }
        Ok(())
    }
}

/// Why a slice stack cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum PrintError {
    #[error("{0}")]
    Pitch(String),
    #[error(
        "a slice stack of {columns} x {rows} droplets and {layers} layers is over the limit of {limit} droplets: use a coarser pitch"
    )]
    TooLarge {
        columns: usize,
        rows: usize,
        layers: usize,
        limit: usize,
    },
    #[error(
        "materials {0} and {1} have the same colour, so a slice could not tell them apart: give them different colours"
    )]
    SameColour(String, String),
}

/// Most droplets a stack may address (about 2.7 × 10⁹: a J750's whole 490 × 390 × 200 mm tray
/// at its finest pitch is 10¹¹, a design of ours is a few centimetres).
pub const MAX_DROPLETS: usize = 1 << 31;

/// The slicer of one design: the genome's field, the task's kept voxels, the printer's pitch.
#[derive(Debug)]
pub struct Slicer<'g> {
    sampler: LayerSampler<'g>,
    /// Droplets along x, y and layers along z.
    counts: [usize; 3],
    pitch_mm: [f64; 3],
    size_mm: [f64; 3],
    voxel_mm: f64,
    dims: GridDims,
    /// Per voxel: whether droplets inside it may take material (see the module note).
    allowed: Vec<bool>,
    material_count: usize,
    threshold: f64,
}

impl<'g> Slicer<'g> {
    /// The slicer of `genome` in `scene`, whose voxel design at `dims` sets the physical size
    /// (dims × the scene's voxel size) and the kept region. The stack covers the design's
    /// bounding workspace: `ceil(size / pitch)` droplets per axis, droplet centres at
    /// `(i + ½) · pitch` from the workspace's corner, so the print is at exact scale.
    pub fn new(
        genome: &'g Genome,
        scene: &Scene,
        dims: GridDims,
        pitch: PrintPitch,
    ) -> Result<Self, PrintError> {
        pitch.validate().map_err(PrintError::Pitch)?;
        let voxel_mm = 1e3 * scene.voxel_size(dims);
        let size_mm = [dims.nx, dims.ny, dims.nz].map(|n| n as f64 * voxel_mm);
        let pitch_mm = pitch.pitch_mm();
        // A design a whole number of droplets wide should not gain a droplet from rounding.
        let counts = [0, 1, 2].map(|a| ((size_mm[a] / pitch_mm[a] - 1e-9).ceil() as usize).max(1));
        let droplets = counts
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n))
            .unwrap_or(usize::MAX);
        if droplets > MAX_DROPLETS {
            return Err(PrintError::TooLarge {
                columns: counts[0],
                rows: counts[1],
                layers: counts[2],
                limit: MAX_DROPLETS,
            });
        }
        let material_count = scene.palette().len();
        let threshold = scene.threshold();
        let raw = voxelize(genome, dims, material_count, threshold);
        let kept = scene.design(genome, dims);
        let allowed = allowed_voxels(&raw, &kept);
        let normalized = |axis: usize| -> Vec<f64> {
            (0..counts[axis])
                .map(|i| (i as f64 + 0.5) * pitch_mm[axis] / size_mm[axis])
                .collect()
        };
        let sampler =
            LayerSampler::new(genome, dims, material_count, &normalized(0), &normalized(1));
        Ok(Slicer {
            sampler,
            counts,
            pitch_mm,
            size_mm,
            voxel_mm,
            dims,
            allowed,
            material_count,
            threshold,
        })
    }

    /// Droplets along x, along y, and layers.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    pub fn pitch_mm(&self) -> [f64; 3] {
        self.pitch_mm
    }

    /// The design's size in millimetres (the workspace the stack covers).
    pub fn size_mm(&self) -> [f64; 3] {
        self.size_mm
    }

    /// Layer `k` (0 = bottom): the material of each droplet, `x + columns · y`.
    pub fn layer(&self, k: usize) -> Vec<Option<MaterialId>> {
        let [nx, ny, _] = self.counts;
        let len = nx * ny;
        let z_mm = (k as f64 + 0.5) * self.pitch_mm[2];
        let mut densities = vec![0.0; self.material_count * len];
        self.sampler
            .accumulate_layer(z_mm / self.size_mm[2], &mut densities, len);
        // A droplet centre past the workspace's far side (the last, partial droplet) is empty.
        let cell = |mm: f64, n: usize| {
            let c = (mm / self.voxel_mm).floor() as usize;
            (c < n).then_some(c)
        };
        let Some(cz) = cell(z_mm, self.dims.nz) else {
            return vec![None; len];
        };
        let columns: Vec<Option<usize>> = (0..nx)
            .map(|i| cell((i as f64 + 0.5) * self.pitch_mm[0], self.dims.nx))
            .collect();
        let mut out = vec![None; len];
        for j in 0..ny {
            let Some(cy) = cell((j as f64 + 0.5) * self.pitch_mm[1], self.dims.ny) else {
                continue;
            };
            for (i, cx) in columns.iter().enumerate() {
                let Some(cx) = *cx else { continue };
                if !self.allowed[self.dims.index(cx, cy, cz)] {
                    continue;
                }
                let s = i + nx * j;
                out[s] = material_at(self.material_count, self.threshold, |m| {
                    densities[m * len + s]
                });
            }
        }
        out
    }
}

/// Per voxel: kept voxels, and empty voxels (in the raw voxelization) next to a kept one. Voxels
/// the raw voxelization filled but the task discarded stay closed.
fn allowed_voxels(raw: &VoxelGrid, kept: &VoxelGrid) -> Vec<bool> {
    let d = kept.dims();
    let mut allowed = vec![false; d.cell_count()];
    for i in kept.filled_indices() {
        for n in d.neighbourhood(i) {
            allowed[n] = kept.cells()[n].is_some() || raw.cells()[n].is_none();
        }
    }
    allowed
}

/// The colour of each material in a slice (index = material id): its palette colour, opaque.
pub fn print_colours(palette: &Palette) -> Result<Vec<[u8; 4]>, PrintError> {
    let colours: Vec<[u8; 4]> = palette
        .0
        .iter()
        .map(|m| [m.colour[0], m.colour[1], m.colour[2], 255])
        .collect();
    for (a, ca) in colours.iter().enumerate() {
        if let Some(b) = colours[..a].iter().position(|cb| cb == ca) {
            return Err(PrintError::SameColour(
                palette.0[b].name.clone(),
                palette.0[a].name.clone(),
            ));
        }
    }
    Ok(colours)
}

/// Encodes one layer as an 8-bit RGBA PNG, seen from above: column = +x, row 0 = the largest y.
pub fn layer_png(
    layer: &[Option<MaterialId>],
    columns: usize,
    colours: &[[u8; 4]],
) -> Result<Vec<u8>, png::EncodingError> {
    let rows = layer.len() / columns.max(1);
    let mut data = Vec::with_capacity(layer.len() * 4);
    for j in (0..rows).rev() {
        for cell in &layer[j * columns..][..columns] {
            data.extend(cell.map_or(VOID_RGBA, |m| colours[m.index()]));
        }
    }
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, columns as u32, rows as u32);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&data)?;
    writer.finish()?;
    Ok(bytes)
}

/// Writes `slices/slice-<k>.png` (k = 1 at the bottom) and `slices/manifest.json` (pitch, size,
/// layer count, the material-to-colour map with each material's droplet count and volume) into
/// `dir`. Returns the files written, relative to `dir`.
pub fn write_slice_stack(
    dir: &Path,
    genome: &Genome,
    scene: &Scene,
    dims: GridDims,
    pitch: PrintPitch,
) -> std::io::Result<Vec<PathBuf>> {
    let slicer = Slicer::new(genome, scene, dims, pitch).map_err(std::io::Error::other)?;
    let colours = print_colours(scene.palette()).map_err(std::io::Error::other)?;
    let [nx, ny, nz] = slicer.counts();
    std::fs::create_dir_all(dir.join("slices"))?;
    let digits = nz.to_string().len().max(4);
    let mut written = Vec::with_capacity(nz + 1);
    let mut droplets = vec![0u64; scene.palette().len()];
    for k in 0..nz {
        let layer = slicer.layer(k);
        for m in layer.iter().flatten() {
            droplets[m.index()] += 1;
        }
        let name = PathBuf::from(format!("slices/slice-{:0digits$}.png", k + 1));
        let png = layer_png(&layer, nx, &colours).map_err(std::io::Error::other)?;
        std::fs::write(dir.join(&name), png)?;
        written.push(name);
    }
    let pitch_mm = slicer.pitch_mm();
    let droplet_mm3 = pitch_mm.iter().product::<f64>();
    let materials: Vec<serde_json::Value> = scene
        .palette()
        .0
        .iter()
        .enumerate()
        .map(|(m, material)| {
            serde_json::json!({
                "index": m,
                "name": material.name,
                "rgba": colours[m],
                "droplets": droplets[m],
                "volume_mm3": droplets[m] as f64 * droplet_mm3,
            })
        })
        .collect();
    let manifest = serde_json::json!({
        "format": "amorph voxel-print slice stack",
        "version": 1,
        "layers": nz,
        "width_px": nx,
        "height_px": ny,
        "dpi": [pitch.dpi_x, pitch.dpi_y],
        "layer_mm": pitch.layer_mm,
        "pitch_mm": pitch_mm,
        "size_mm": slicer.size_mm(),
        "orientation": "slice-1 is the bottom layer (z = 0); in each image, columns run along +x and row 0 is the largest y (seen from above)",
        "void_rgba": VOID_RGBA,
        "materials": materials,
    });
    let name = PathBuf::from("slices/manifest.json");
    std::fs::write(
        dir.join(&name),
        serde_json::to_string_pretty(&manifest).map_err(std::io::Error::other)?,
    )?;
    written.push(name);
    Ok(written)
}
