//! An animated GIF of a robot walking, from a [`LocomotionRecording`]: each frame draws every
//! voxel as a shaded cube at its simulated position and orientation, materials in their colours,
//! on a floor with a grid (so motion reads against it), seen isometrically as [`render_isometric`]
//! sees a design, with the cycle and time as a caption.
//!
//! Every colour a frame can contain is known in advance (a few per material), so frames are drawn
//! in RGB and mapped exactly onto one global palette: no quantisation. To stay small, each frame
//! after the first stores only the rectangle that changed, with unchanged pixels transparent,
//! which the LZW coder compresses to almost nothing.
//!
//! [`render_isometric`]: crate::report::render_isometric

use std::collections::HashMap;
use std::io::Write;

use super::recording::{LocomotionRecording, RecordingOptions, record_locomotion};
use super::{LocomotionPhase, LocomotionScene};
use crate::dynamics::{Quat, Vec3};
use crate::genome::Genome;
use crate::material::Palette;
use crate::report::{Image, fill_quad, line, text};
use crate::voxel::GridDims;

/// Brightness of faces whose normal points mostly up, along +x and along +y (as the still render).
const SHADE: [f64; 3] = [1.0, 0.78, 0.6];
/// Edge pixels of a face, relative to its fill.
const EDGE: f64 = 0.55;
const BACKGROUND: [u8; 3] = [255, 255, 255];
const FLOOR: [u8; 3] = [238, 238, 230];
const GRID_LINE: [u8; 3] = [180, 180, 168];
const INK: [u8; 3] = [30, 30, 30];
/// Height of the caption band above the scene, px.
const CAPTION_PX: usize = 24;
/// Blank border around the scene, px.
const MARGIN_PX: f64 = 6.0;
/// Floor shown beyond the robot's reach on every side, in voxel sizes.
const FLOOR_BORDER_VOXELS: f64 = 3.0;

/// How the GIF looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimationOptions {
    /// Longest side of the picture, px (default 360).
    pub max_side_px: usize,
    /// Time each frame is shown, hundredths of a second (default 7: ~14 frames per second, so
    /// ten frames per cycle play a cycle in 0.7 s, ten times slower than the paper's robot).
    pub frame_delay_cs: u16,
    /// Outline every voxel face (default false). Outlines show the voxels but move with every
    /// sub-pixel deformation, which the frame-difference coding cannot skip: measured on a
    /// 1,006-voxel robot, 101 frames at 360 px took 512 KB with outlines and 253 KB without.
    pub voxel_edges: bool,
}

impl Default for AnimationOptions {
    fn default() -> Self {
        Self {
            max_side_px: 360,
            frame_delay_cs: 7,
            voxel_edges: false,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum AnimationError {
    #[error("the recording has no frames")]
    NoFrames,
    #[error("{0} materials need more than the 256 colours a GIF palette holds")]
    TooManyMaterials(usize),
    #[error("gif: {0}")]
    Gif(#[from] gif::EncodingError),
    #[error("writing the gif: {0}")]
    Io(#[from] std::io::Error),
}

/// Simulates the robot `genome` makes at `dims` (recording as `recording` says), writes its GIF
/// to `out` and returns the recording, e.g. for a trajectory plot of the same run.
pub fn write_locomotion_animation(
    genome: &Genome,
    scene: &LocomotionScene,
    dims: GridDims,
    recording: RecordingOptions,
    options: AnimationOptions,
    out: &mut impl Write,
) -> Result<LocomotionRecording, AnimationError> {
    let recorded = record_locomotion(genome, scene, dims, recording);
    let gif = animation_gif(&recorded, &scene.palette, options)?;
    out.write_all(&gif)?;
    Ok(recorded)
}

/// Encodes every frame of `recording` as a looping GIF.
pub fn animation_gif(
    recording: &LocomotionRecording,
    palette: &Palette,
    options: AnimationOptions,
) -> Result<Vec<u8>, AnimationError> {
    if recording.frames.is_empty() || recording.voxel_count() == 0 {
        return Err(AnimationError::NoFrames);
    }
    let colours = Colours::new(palette)?;
    let view = View::fit(recording, options.max_side_px);
    let exposed = exposed_faces(&recording.cells);
    let mut order: Vec<usize> = (0..recording.voxel_count()).collect();

    let mut bytes = Vec::new();
    let mut encoder = gif::Encoder::new(
        &mut bytes,
        view.width as u16,
        view.height as u16,
        &colours.rgb_table(),
    )?;
    encoder.set_repeat(gif::Repeat::Infinite)?;
    let mut previous: Option<Vec<u8>> = None;
    let mut image = Image {
        width: view.width,
        height: view.height,
        pixels: vec![BACKGROUND; view.width * view.height],
    };
    for k in 0..recording.frames.len() {
        image.pixels.fill(BACKGROUND);
        view.draw_floor(&mut image);
        let (positions, orientations) = recording.frame(k);
        // Painter's algorithm: far to near along the view direction (1, 1, 1).
        order.sort_by(|&a, &b| {
            let depth = |i: usize| positions[i].iter().map(|&c| f64::from(c)).sum::<f64>();
            depth(a).total_cmp(&depth(b))
        });
        for &i in &order {
            let q = orientations[i];
            let rotation = Quat {
                w: f64::from(q[0]),
                x: f64::from(q[1]),
                y: f64::from(q[2]),
                z: f64::from(q[3]),
            };
            let p = positions[i].map(f64::from);
            let material = recording.materials[i].index();
            view.draw_voxel(
                &mut image,
                Vec3::new(p[0], p[1], p[2]),
                rotation,
                exposed[i],
                palette.0[material].colour,
                options.voxel_edges,
            );
        }
        text(&mut image, &caption(recording, k), 6.0, 5.0, INK);
        let indices = colours.indices(&image);
        let mut frame = match &previous {
            None => gif::Frame {
                width: view.width as u16,
                height: view.height as u16,
                buffer: indices.as_slice().into(),
                ..gif::Frame::default()
            },
            Some(before) => changed_rectangle(before, &indices, view.width, colours.transparent),
        };
        frame.delay = options.frame_delay_cs;
        // The settled pose is held a little longer so the loop reads as a restart.
        if k == 0 {
            frame.delay = options.frame_delay_cs.saturating_mul(4);
        }
        frame.dispose = gif::DisposalMethod::Keep;
        encoder.write_frame(&frame)?;
        previous = Some(indices);
    }
    drop(encoder);
    Ok(bytes)
}

fn caption(recording: &LocomotionRecording, k: usize) -> String {
    let sample = recording.frames[k];
    match sample.phase {
        LocomotionPhase::Actuating { cycle, .. } => {
            let start = recording.frames[0].time;
            format!(
                "CYCLE {}/{}  T = {:.3} S",
                cycle + 1,
                recording.cycles,
                sample.time - start
            )
        }
        _ => "SETTLED".into(),
    }
}

/// The part of `after` that differs from `before`, as a frame at its offset, with pixels that
/// did not change set to `transparent` (a 1×1 transparent frame when nothing changed).
fn changed_rectangle(
    before: &[u8],
    after: &[u8],
    width: usize,
    transparent: u8,
) -> gif::Frame<'static> {
    let height = after.len() / width;
    let (mut x0, mut y0, mut x1, mut y1) = (width, height, 0, 0);
    for y in 0..height {
        for x in 0..width {
            if before[y * width + x] != after[y * width + x] {
                (x0, y0) = (x0.min(x), y0.min(y));
                (x1, y1) = (x1.max(x + 1), y1.max(y + 1));
            }
        }
    }
    if x1 == 0 {
        (x0, y0, x1, y1) = (0, 0, 1, 1);
    }
    let mut buffer = Vec::with_capacity((x1 - x0) * (y1 - y0));
    for y in y0..y1 {
        for x in x0..x1 {
            let (b, a) = (before[y * width + x], after[y * width + x]);
            buffer.push(if a == b { transparent } else { a });
        }
    }
    gif::Frame {
        left: x0 as u16,
        top: y0 as u16,
        width: (x1 - x0) as u16,
        height: (y1 - y0) as u16,
        transparent: Some(transparent),
        buffer: buffer.into(),
        ..gif::Frame::default()
    }
}

/// The global palette: background, floor, grid, ink, then per material three face fills and
/// their three edge colours; one more index is left for "unchanged" (transparent).
struct Colours {
    table: Vec<[u8; 3]>,
    index: HashMap<[u8; 3], u8>,
    transparent: u8,
}

impl Colours {
    fn new(palette: &Palette) -> Result<Self, AnimationError> {
        let mut table = vec![BACKGROUND, FLOOR, GRID_LINE, INK];
        for (_, material) in palette.iter() {
            for shade in SHADE {
                table.push(shaded(material.colour, shade));
                table.push(shaded(material.colour, shade * EDGE));
            }
        }
        if table.len() >= 256 {
            return Err(AnimationError::TooManyMaterials(palette.len()));
        }
        let mut index = HashMap::new();
        for (i, &c) in table.iter().enumerate() {
            index.entry(c).or_insert(i as u8);
        }
        let transparent = table.len() as u8;
        Ok(Self {
            table,
            index,
            transparent,
        })
    }

    fn rgb_table(&self) -> Vec<u8> {
        let mut rgb: Vec<u8> = self.table.iter().flatten().copied().collect();
        // The transparent entry's colour is never shown.
        rgb.extend_from_slice(&BACKGROUND);
        rgb
    }

    /// Palette indices of a frame; every pixel was drawn in a palette colour.
    fn indices(&self, image: &Image) -> Vec<u8> {
        image
            .pixels
            .iter()
            .map(|p| self.index.get(p).copied().unwrap_or(0))
            .collect()
    }
}

fn shaded(colour: [u8; 3], factor: f64) -> [u8; 3] {
    colour.map(|c| (f64::from(c) * factor).round() as u8)
}

/// For each voxel, a bit per local face direction (+x, −x, +y, −y, +z, −z) whose neighbour in
/// the rest lattice is empty: only those faces can be seen.
fn exposed_faces(cells: &[[u16; 3]]) -> Vec<u8> {
    let n = [0, 1, 2].map(|a| {
        cells
            .iter()
            .map(|c| usize::from(c[a]) + 1)
            .max()
            .unwrap_or(0)
    });
    let mut filled = vec![false; n[0] * n[1] * n[2]];
    let at = |c: [usize; 3]| c[0] + n[0] * (c[1] + n[1] * c[2]);
    for c in cells {
        filled[at(c.map(usize::from))] = true;
    }
    cells
        .iter()
        .map(|c| {
            let c = c.map(usize::from);
            let mut mask = 0u8;
            for (bit, (axis, positive)) in FACES.iter().enumerate() {
                let mut next = c;
                let inside = if *positive {
                    next[*axis] += 1;
                    next[*axis] < n[*axis]
                } else if next[*axis] > 0 {
                    next[*axis] -= 1;
                    true
                } else {
                    false
                };
                if !inside || !filled[at(next)] {
                    mask |= 1 << bit;
                }
            }
            mask
        })
        .collect()
}

/// Local face directions in the order of the [`exposed_faces`] bits: (axis, positive).
const FACES: [(usize, bool); 6] = [
    (0, true),
    (0, false),
    (1, true),
    (1, false),
    (2, true),
    (2, false),
];

/// Where the world lands on the picture.
struct View {
    width: usize,
    height: usize,
    /// Pixels per metre.
    scale: f64,
    /// Screen offset added after projection, px.
    offset: [f64; 2],
    voxel_size: f64,
    /// The floor rectangle (x0, y0, x1, y1), m, and its grid spacing, m.
    floor: [f64; 4],
    grid: f64,
}

impl View {
    /// Screen coordinates (unscaled) of a world point: right = (x − y) cos 30°, down =
    /// (x + y) sin 30° − z.
    fn project_unscaled(p: Vec3) -> [f64; 2] {
        let cos30 = 3f64.sqrt() / 2.0;
        [(p.x - p.y) * cos30, (p.x + p.y) * 0.5 - p.z]
    }

    fn to_pixel(&self, p: Vec3) -> [f64; 2] {
        let s = Self::project_unscaled(p);
        [
            s[0] * self.scale + self.offset[0],
            s[1] * self.scale + self.offset[1],
        ]
    }

    /// A fixed camera that keeps the floor and every voxel of every frame in the picture.
    fn fit(recording: &LocomotionRecording, max_side_px: usize) -> Self {
        let s = recording.voxel_size;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for k in 0..recording.frames.len() {
            for p in recording.frame(k).0 {
                for a in 0..3 {
                    lo[a] = lo[a].min(f64::from(p[a]));
                    hi[a] = hi[a].max(f64::from(p[a]));
                }
            }
        }
        let border = FLOOR_BORDER_VOXELS * s;
        let floor = [
            lo[0] - border,
            lo[1] - border,
            hi[0] + border,
            hi[1] + border,
        ];
        let grid = nice_spacing((floor[2] - floor[0]).max(floor[3] - floor[1]) / 8.0);
        // A rotated cube reaches at most √3/2 s from its centre, which projects to at most
        // 1.1 s on screen.
        let reach = 1.1 * s;
        let mut screen_lo = [f64::INFINITY; 2];
        let mut screen_hi = [f64::NEG_INFINITY; 2];
        let mut include = |q: [f64; 2], pad: f64| {
            for a in 0..2 {
                screen_lo[a] = screen_lo[a].min(q[a] - pad);
                screen_hi[a] = screen_hi[a].max(q[a] + pad);
            }
        };
        for x in [floor[0], floor[2]] {
            for y in [floor[1], floor[3]] {
                include(Self::project_unscaled(Vec3::new(x, y, 0.0)), 0.0);
            }
        }
        for x in [lo[0], hi[0]] {
            for y in [lo[1], hi[1]] {
                for z in [lo[2], hi[2]] {
                    include(Self::project_unscaled(Vec3::new(x, y, z)), reach);
                }
            }
        }
        let extent = [screen_hi[0] - screen_lo[0], screen_hi[1] - screen_lo[1]];
        let usable = max_side_px as f64 - 2.0 * MARGIN_PX;
        let scale = usable / extent[0].max(extent[1]);
        let width = (extent[0] * scale + 2.0 * MARGIN_PX).ceil() as usize;
        let height = (extent[1] * scale + 2.0 * MARGIN_PX).ceil() as usize + CAPTION_PX;
        Self {
            width,
            height,
            scale,
            offset: [
                MARGIN_PX - screen_lo[0] * scale,
                MARGIN_PX + CAPTION_PX as f64 - screen_lo[1] * scale,
            ],
            voxel_size: s,
            floor,
            grid,
        }
    }

    fn draw_floor(&self, image: &mut Image) {
        let [x0, y0, x1, y1] = self.floor;
        let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
            .map(|(x, y)| self.to_pixel(Vec3::new(x, y, 0.0)));
        fill_quad(image, corners, FLOOR, FLOOR);
        let g = self.grid;
        let mut x = (x0 / g).ceil() * g;
        while x <= x1 {
            let (a, b) = (Vec3::new(x, y0, 0.0), Vec3::new(x, y1, 0.0));
            line(image, self.to_pixel(a), self.to_pixel(b), GRID_LINE, 1);
            x += g;
        }
        let mut y = (y0 / g).ceil() * g;
        while y <= y1 {
            let (a, b) = (Vec3::new(x0, y, 0.0), Vec3::new(x1, y, 0.0));
            line(image, self.to_pixel(a), self.to_pixel(b), GRID_LINE, 1);
            y += g;
        }
    }

    /// The cube of a voxel centred at `centre`, rotated by `rotation`: its exposed faces that
    /// face the viewer, shaded by the world direction they face.
    fn draw_voxel(
        &self,
        image: &mut Image,
        centre: Vec3,
        rotation: Quat,
        exposed: u8,
        colour: [u8; 3],
        outlined: bool,
    ) {
        let h = 0.5 * self.voxel_size;
        let toward_viewer = Vec3::new(1.0, 1.0, 1.0);
        for (bit, &(axis, positive)) in FACES.iter().enumerate() {
            if exposed & (1 << bit) == 0 {
                continue;
            }
            let sign = if positive { 1.0 } else { -1.0 };
            let local = |a: usize, v: f64| {
                let mut e = [0.0; 3];
                e[a] = v;
                Vec3::new(e[0], e[1], e[2])
            };
            let normal = rotation.rotate(local(axis, sign));
            if normal.dot(toward_viewer) <= 0.0 {
                continue;
            }
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let face_centre = centre + rotation.rotate(local(axis, sign * h));
            let corners = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(du, dv)| {
                self.to_pixel(face_centre + rotation.rotate(local(u, du) + local(v, dv)))
            });
            // The brightest shade for up-facing, then +x, then +y, as the still render.
            let slot = [normal.z, normal.x, normal.y]
                .into_iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(slot, _)| slot);
            let fill = shaded(colour, SHADE[slot]);
            let edge = shaded(colour, SHADE[slot] * if outlined { EDGE } else { 1.0 });
            fill_quad(image, corners, fill, edge);
        }
    }
}

/// The 1-2-5 number nearest above `raw`, for grid lines.
fn nice_spacing(raw: f64) -> f64 {
    let magnitude = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude)
}
