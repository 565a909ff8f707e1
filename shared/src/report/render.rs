//! A picture of a design: an isometric view of its voxels, each material in its colour, the three
//! visible face directions shaded differently so the shape reads, written as PNG.
//!
//! The viewer looks down the (−1, −1, −1) diagonal, so the +x, +y and +z faces of a voxel can be
//! seen; unit cubes drawn far to near (increasing x + y + z) occlude correctly (painter's
//! algorithm), and only faces whose neighbour is empty are drawn.

use crate::material::Palette;
use crate::voxel::VoxelGrid;

/// Brightness of the +z (top), +x and +y faces.
const SHADE: [f64; 3] = [1.0, 0.78, 0.6];
const BACKGROUND: [u8; 3] = [255, 255, 255];

/// An RGB image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    /// Encodes as an 8-bit RGB PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        let data: Vec<u8> = self.pixels.iter().flatten().copied().collect();
        writer.write_image_data(&data)?;
        writer.finish()?;
        Ok(bytes)
    }
}

/// Renders `grid` isometrically with each voxel edge `voxel_px` pixels long on screen.
pub fn render_isometric(grid: &VoxelGrid, palette: &Palette, voxel_px: f64) -> Image {
    let d = grid.dims();
    let (cos30, sin30) = (3f64.sqrt() / 2.0, 0.5);
    // Screen position of lattice point (x, y, z): right = (x − y) cos 30°, down = (x + y) sin 30° − z.
    let project = |p: [f64; 3]| {
        [
            (p[0] - p[1]) * cos30 * voxel_px,
            ((p[0] + p[1]) * sin30 - p[2]) * voxel_px,
        ]
    };
    let (nx, ny, nz) = (d.nx as f64, d.ny as f64, d.nz as f64);
    let corners = [
        [0.0, 0.0, 0.0],
        [nx, 0.0, 0.0],
        [0.0, ny, 0.0],
        [nx, ny, 0.0],
        [0.0, 0.0, nz],
        [nx, 0.0, nz],
        [0.0, ny, nz],
        [nx, ny, nz],
    ]
    .map(project);
    let margin = 2.0 * voxel_px.max(2.0);
    let min = [0, 1].map(|a| corners.iter().map(|c| c[a]).fold(f64::INFINITY, f64::min));
    let max = [0, 1].map(|a| {
        corners
            .iter()
            .map(|c| c[a])
            .fold(f64::NEG_INFINITY, f64::max)
    });
    let width = (max[0] - min[0] + 2.0 * margin).ceil() as usize;
    let height = (max[1] - min[1] + 2.0 * margin).ceil() as usize;
    let mut image = Image {
        width,
        height,
        pixels: vec![BACKGROUND; width * height],
    };
    let to_pixel = |p: [f64; 3]| {
        let s = project(p);
        [s[0] - min[0] + margin, s[1] - min[1] + margin]
    };

    let mut order: Vec<[usize; 3]> = (0..d.nz)
        .flat_map(|z| (0..d.ny).flat_map(move |y| (0..d.nx).map(move |x| [x, y, z])))
        .filter(|&[x, y, z]| grid.get(x, y, z).is_some())
        .collect();
    order.sort_by_key(|&[x, y, z]| (x + y + z, z));
    let empty = |x: usize, y: usize, z: usize| {
        x >= d.nx || y >= d.ny || z >= d.nz || grid.get(x, y, z).is_none()
    };
    for [x, y, z] in order {
        let Some(material) = grid.get(x, y, z) else {
            continue;
        };
        let colour = palette.get(material).colour;
        let (fx, fy, fz) = (x as f64, y as f64, z as f64);
        // Top (+z), then +x, then +y: quads as lattice points.
        let faces = [
            (
                empty(x, y, z + 1),
                [[0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.]],
                SHADE[0],
            ),
            (
                empty(x + 1, y, z),
                [[1., 0., 0.], [1., 1., 0.], [1., 1., 1.], [1., 0., 1.]],
                SHADE[1],
            ),
            (
                empty(x, y + 1, z),
                [[0., 1., 0.], [0., 1., 1.], [1., 1., 1.], [1., 1., 0.]],
                SHADE[2],
            ),
        ];
        for (visible, quad, shade) in faces {
            if !visible {
                continue;
            }
            let q = quad.map(|c| to_pixel([fx + c[0], fy + c[1], fz + c[2]]));
            let fill = colour.map(|c| (f64::from(c) * shade).round() as u8);
            let edge = colour.map(|c| (f64::from(c) * shade * 0.55).round() as u8);
            fill_quad(&mut image, q, fill, edge);
        }
    }
    image
}

/// Fills a convex quad, drawing pixels within half a pixel of its border in `edge` so voxels
/// stay distinguishable.
pub(crate) fn fill_quad(image: &mut Image, q: [[f64; 2]; 4], fill: [u8; 3], edge: [u8; 3]) {
    let lo = [0, 1].map(|a| q.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min));
    let hi = [0, 1].map(|a| q.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max));
    let area2: f64 = (0..4)
        .map(|i| {
            let (a, b) = (q[i], q[(i + 1) % 4]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let orientation = area2.signum();
    for py in lo[1].floor().max(0.0) as usize..(hi[1].ceil() as usize).min(image.height) {
        for px in lo[0].floor().max(0.0) as usize..(hi[0].ceil() as usize).min(image.width) {
            let p = [px as f64 + 0.5, py as f64 + 0.5];
            // Signed distance to each side, positive inside.
            let mut nearest = f64::INFINITY;
            for i in 0..4 {
                let (a, b) = (q[i], q[(i + 1) % 4]);
                let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
                let cross = ex * (p[1] - a[1]) - ey * (p[0] - a[0]);
                nearest = nearest.min(orientation * cross / (ex * ex + ey * ey).sqrt());
            }
            if nearest >= 0.0 {
                image.pixels[py * image.width + px] = if nearest < 0.75 { edge } else { fill };
            }
        }
    }
}
