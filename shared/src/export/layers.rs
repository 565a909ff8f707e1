//! Laser-cut layers (paper §IV-C: the robot was cut layer by layer from foam sheets and stacked on
//! alignment pins): one SVG per voxel layer, each material's regions as closed cut paths in
//! millimetres (holes as inner contours wound the other way), the same alignment holes in every
//! layer, the layer number engraved and a scale bar.

use std::fmt::Write;

use crate::material::{MaterialId, Palette};
use crate::voxel::VoxelGrid;

/// Margin between the design and the sheet edge, and the alignment holes' distance from the
/// design, mm.
const MARGIN_MM: f64 = 6.0;
/// Alignment hole diameter, mm (a 2 mm pin).
const PIN_DIAMETER_MM: f64 = 2.0;
/// Scale bar length, mm.
const SCALE_BAR_MM: f64 = 10.0;
/// Room for the scale bar's label ("10 mm" at 2.5 mm type) after a 1 mm gap, mm.
const LABEL_MM: f64 = 9.0;

/// A closed contour in layer coordinates (units of voxels, x right, y up), counter-clockwise
/// around material, clockwise around holes.
pub type Contour = Vec<[i64; 2]>;

/// The contours of material `material`'s cells in layer `z`: every cell side between the
/// material and anything else, chained into closed loops, collinear runs merged. Where two
/// cells touch only at a corner the loops are kept apart (the chain turns left), so every unit
/// side belongs to exactly one loop and no loop crosses itself.
pub fn layer_contours(grid: &VoxelGrid, z: usize, material: MaterialId) -> Vec<Contour> {
    let d = grid.dims();
    let is = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && (x as usize) < d.nx
            && (y as usize) < d.ny
            && grid.get(x as usize, y as usize, z) == Some(material)
    };
    // Directed unit sides, material on the left: bottom side runs +x, right +y, top −x, left −y.
    let mut sides: Vec<([i64; 2], [i64; 2])> = Vec::new();
    for y in 0..d.ny as i64 {
        for x in 0..d.nx as i64 {
            if !is(x, y) {
                continue;
            }
            if !is(x, y - 1) {
                sides.push(([x, y], [x + 1, y]));
            }
            if !is(x + 1, y) {
                sides.push(([x + 1, y], [x + 1, y + 1]));
            }
            if !is(x, y + 1) {
                sides.push(([x + 1, y + 1], [x, y + 1]));
            }
            if !is(x - 1, y) {
                sides.push(([x, y + 1], [x, y]));
            }
        }
    }
    let width = d.nx as i64 + 1;
    let key = |p: [i64; 2]| (p[0] + width * p[1]) as usize;
    let mut outgoing: Vec<Vec<usize>> = vec![Vec::new(); (width * (d.ny as i64 + 1)) as usize];
    for (i, &(from, _)) in sides.iter().enumerate() {
        outgoing[key(from)].push(i);
    }
    let mut used = vec![false; sides.len()];
    let mut contours = Vec::new();
    for start in 0..sides.len() {
        if used[start] {
            continue;
        }
        let mut loop_points = Vec::new();
        let mut current = start;
        loop {
            used[current] = true;
            let (from, to) = sides[current];
            loop_points.push(from);
            let direction = [to[0] - from[0], to[1] - from[1]];
            // At a corner contact two sides leave `to`; take the left turn so the material's
            // loops stay separate.
            let next = outgoing[key(to)]
                .iter()
                .copied()
                .filter(|&j| !used[j] || j == start)
                .max_by_key(|&j| {
                    let (a, b) = sides[j];
                    let turn = [b[0] - a[0], b[1] - a[1]];
                    // cross > 0 is a left turn, then straight, then right.
                    direction[0] * turn[1] - direction[1] * turn[0]
                });
            match next {
                Some(j) if j == start => break,
                Some(j) => current = j,
                None => break,
            }
        }
        contours.push(merge_collinear(loop_points));
    }
    contours
}

/// Drops the points where a contour goes straight on.
fn merge_collinear(points: Vec<[i64; 2]>) -> Contour {
    let n = points.len();
    (0..n)
        .filter(|&i| {
            let (p, q, r) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
            (q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0]) != 0
        })
        .map(|i| points[i])
        .collect()
}

/// The alignment hole centres in millimetres, relative to the design's corner: one beyond each
/// corner of the grid's footprint, so every layer of the stack has them at the same place.
pub fn alignment_holes_mm(grid: &VoxelGrid, voxel_size: f64) -> [[f64; 2]; 3] {
    let d = grid.dims();
    let (w, h) = (
        d.nx as f64 * voxel_size * 1e3,
        d.ny as f64 * voxel_size * 1e3,
    );
    let o = MARGIN_MM / 2.0;
    // Three, not four, so a flipped layer does not fit.
    [[-o, -o], [w + o, -o], [-o, h + o]]
}

/// Stroke of every cut (material outlines, alignment holes): pure red, the colour laser drivers
/// (Epilog, Trotec, Universal, LightBurn's defaults) and shops map to "vector cut".
const CUT_STROKE: &str = "#ff0000";
/// Stroke of vector engraving (the scale bar): pure blue, the usual "score" colour.
const SCORE_STROKE: &str = "#0000ff";
/// Fill of raster engraving (the layer number and labels): black.
const RASTER_FILL: &str = "#000000";
/// Hairline, mm: 0.001 in, which drivers take as a vector line rather than a shape to raster.
const HAIRLINE_MM: f64 = 0.0254;

/// One SVG sheet for layer `z`, in the colour and line conventions laser software expects: each
/// material's outlines as red hairline cuts in a layer named after the material (so one stock sheet
/// per material can be cut with the others hidden; holes written before the outline around them so
/// a driver cutting in file order frees the inner scrap while the part is still held), the
/// alignment holes as cuts, the layer number engraved in black and a scale bar scored in blue.
/// Millimetres throughout (the SVG's user unit is 1 mm), y pointing down the sheet with the
/// design's y up.
pub fn layer_svg(grid: &VoxelGrid, palette: &Palette, voxel_size: f64, z: usize) -> String {
    let d = grid.dims();
    let s = voxel_size * 1e3;
    let (w, h) = (d.nx as f64 * s, d.ny as f64 * s);
    // Wide enough for the scale bar and its label under a narrow design.
    let sheet_w = (w + 2.0 * MARGIN_MM).max(2.0 * MARGIN_MM + SCALE_BAR_MM + LABEL_MM);
    let sheet_h = h + 2.0 * MARGIN_MM + 8.0;
    // Design coordinates (mm, y up, corner at 0) to sheet coordinates.
    let to_sheet = |x: f64, y: f64| (x + MARGIN_MM, MARGIN_MM + h - y);
    let mut out = String::new();
    let o = &mut out;
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" width="{sheet_w}mm" height="{sheet_h}mm" viewBox="0 0 {sheet_w} {sheet_h}">"#
    );
    let _ = writeln!(o, "<title>layer {} of {}</title>", z + 1, d.nz);
    for (id, material) in palette.iter() {
        let mut contours = layer_contours(grid, z, id);
        if contours.is_empty() {
            continue;
        }
        // Holes (clockwise, negative area) first: inner cuts before outer ones.
        contours.sort_by_key(|c| signed_area(c) > 0);
        let [r, g, b] = material.colour;
        let mut path = String::new();
        for contour in &contours {
            for (i, p) in contour.iter().enumerate() {
                let (x, y) = to_sheet(p[0] as f64 * s, p[1] as f64 * s);
                let _ = write!(path, "{}{x} {y} ", if i == 0 { "M" } else { "L" });
            }
            path.push_str("Z ");
        }
        let name = super::xml_escape(&material.name);
        let _ = writeln!(
            o,
            r#"<g id="material-{}" inkscape:groupmode="layer" inkscape:label="cut {name}" data-colour="rgb({r},{g},{b})"><path class="cut" data-material="{}" fill="none" stroke="{CUT_STROKE}" stroke-width="{HAIRLINE_MM}" d="{}"/></g>"#,
            id.index(),
            id.index(),
            path.trim_end()
        );
    }
    let _ = writeln!(
        o,
        r#"<g id="alignment" inkscape:groupmode="layer" inkscape:label="cut alignment holes">"#
    );
    for [x, y] in alignment_holes_mm(grid, voxel_size) {
        let (cx, cy) = to_sheet(x, y);
        let _ = writeln!(
            o,
            r#"<circle class="alignment" cx="{cx}" cy="{cy}" r="{}" fill="none" stroke="{CUT_STROKE}" stroke-width="{HAIRLINE_MM}"/>"#,
            PIN_DIAMETER_MM / 2.0
        );
    }
    let _ = writeln!(o, "</g>");
    let (tx, ty) = to_sheet(w + MARGIN_MM / 2.0, h + MARGIN_MM / 2.0);
    let bar_y = sheet_h - 4.0;
    let _ = writeln!(
        o,
        r#"<g id="engrave" inkscape:groupmode="layer" inkscape:label="engrave"><text class="engrave" x="{tx}" y="{ty}" font-size="3" font-family="sans-serif" text-anchor="end" fill="{RASTER_FILL}">{}</text>"#,
        z + 1
    );
    let _ = writeln!(
        o,
        r#"<g class="score scale-bar"><line x1="{MARGIN_MM}" y1="{bar_y}" x2="{}" y2="{bar_y}" fill="none" stroke="{SCORE_STROKE}" stroke-width="{HAIRLINE_MM}"/><text x="{}" y="{}" font-size="2.5" font-family="sans-serif" fill="{RASTER_FILL}">{SCALE_BAR_MM} mm</text></g></g>"#,
        MARGIN_MM + SCALE_BAR_MM,
        MARGIN_MM + SCALE_BAR_MM + 1.0,
        bar_y + 1.0
    );
    let _ = writeln!(o, "</svg>");
    out
}

/// Twice the signed area of a contour in voxel units: positive around material, negative around
/// a hole.
fn signed_area(contour: &Contour) -> i64 {
    let n = contour.len();
    (0..n)
        .map(|i| {
            let (p, q) = (contour[i], contour[(i + 1) % n]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum()
}
