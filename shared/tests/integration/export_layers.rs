//! Laser-cut layers: contours are closed, use every cell side exactly once, enclose exactly the
//! material's area with holes wound the other way; the SVG sheets parse and their alignment holes
//! coincide in every layer.

use std::collections::HashSet;

use amorph::export::{layer_contours, layer_svg};
use amorph::material::{MaterialId, Palette};
use amorph::voxel::GridDims;
use proptest::prelude::*;

use crate::common::grid_from;

fn signed_area(contour: &[[i64; 2]]) -> i64 {
    let n = contour.len();
    (0..n)
        .map(|i| {
            let (p, q) = (contour[i], contour[(i + 1) % n]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum::<i64>()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn contours_are_closed_disjoint_and_enclose_the_material(
        cells in prop::collection::vec(0u8..3, 6 * 5),
    ) {
        let dims = GridDims::new(6, 5, 1);
        let grid = grid_from(dims, &cells);
        for m in 0..2u8 {
            let contours = layer_contours(&grid, 0, MaterialId(m));
            let count = cells.iter().filter(|&&c| c == m + 1).count() as i64;
            // Shoelace: CCW outlines count positive, CW holes negative; twice the area.
            let area: i64 = contours.iter().map(|c| signed_area(c)).sum();
            prop_assert_eq!(area, 2 * count);
            // Unit sides (after re-expanding merged runs) are never repeated, and a loop
            // revisits a point only where two cells of the material touch at that corner alone
            // (it then touches itself there without crossing).
            let is = |x: i64, y: i64| {
                (0..6).contains(&x) && (0..5).contains(&y) && cells[(x + 6 * y) as usize] == m + 1
            };
            let mut sides = HashSet::new();
            for c in &contours {
                prop_assert!(c.len() >= 4);
                let mut points = HashSet::new();
                for p in c {
                    if !points.insert(p) {
                        let [x, y] = *p;
                        let around = [is(x - 1, y - 1), is(x, y - 1), is(x - 1, y), is(x, y)];
                        let diagonal = around == [true, false, false, true]
                            || around == [false, true, true, false];
                        prop_assert!(diagonal, "loop revisits {p:?}, not a corner contact");
                    }
                }
                for i in 0..c.len() {
                    let (p, q) = (c[i], c[(i + 1) % c.len()]);
                    let step = [(q[0] - p[0]).signum(), (q[1] - p[1]).signum()];
                    prop_assert!(step[0] == 0 || step[1] == 0, "diagonal edge {p:?}->{q:?}");
                    let mut a = p;
                    while a != q {
                        let b = [a[0] + step[0], a[1] + step[1]];
                        let side = (a.min(b), a.max(b));
                        prop_assert!(sides.insert(side), "side {side:?} cut twice");
                        a = b;
                    }
                }
            }
        }
    }
}

#[test]
fn a_ring_has_an_outline_and_a_hole_wound_the_other_way() {
    let dims = GridDims::new(3, 3, 1);
    let grid = grid_from(dims, &[1, 1, 1, 1, 0, 1, 1, 1, 1]);
    let contours = layer_contours(&grid, 0, MaterialId(0));
    let mut areas: Vec<i64> = contours.iter().map(|c| signed_area(c)).collect();
    areas.sort();
    assert_eq!(areas, vec![-2, 18]);
}

#[test]
fn every_sheet_parses_and_the_alignment_holes_coincide() {
    let dims = GridDims::new(4, 3, 3);
    let cells: Vec<u8> = (0..36).map(|i| [0, 1, 2, 1, 1][i % 5]).collect();
    let grid = grid_from(dims, &cells);
    let palette = Palette::hard_soft_resins();
    let mut holes = Vec::new();
    for z in 0..3 {
        let svg = layer_svg(&grid, &palette, 1e-3, z);
        let doc = roxmltree::Document::parse(&svg).expect("well-formed SVG");
        let circles: Vec<(String, String)> = doc
            .descendants()
            .filter(|n| n.has_tag_name("circle"))
            .map(|n| {
                (
                    n.attribute("cx").unwrap().into(),
                    n.attribute("cy").unwrap().into(),
                )
            })
            .collect();
        assert_eq!(circles.len(), 3);
        holes.push(circles);
        for path in doc.descendants().filter(|n| n.has_tag_name("path")) {
            let d = path.attribute("d").unwrap();
            assert!(d.starts_with('M') && d.ends_with('Z'), "{d}");
        }
        let number = doc
            .descendants()
            .find(|n| n.attribute("class") == Some("engrave"))
            .and_then(|n| n.text())
            .unwrap();
        assert_eq!(number, (z + 1).to_string());
    }
    assert!(holes.windows(2).all(|w| w[0] == w[1]));
}

/// The sheet follows the colour and line conventions laser drivers map to operations: every cut
/// (outlines, alignment holes) is an unfilled pure-red hairline of at most 0.001 in, nothing else
/// is red; engraving is black text or a blue hairline; each material's cuts sit in a layer named
/// after the material; a ring's hole is cut before its outline.
#[test]
fn cuts_are_red_hairlines_in_a_layer_per_material_with_holes_first() {
    // A ring of material 0 around one cell of material 1.
    let grid = grid_from(GridDims::new(3, 3, 1), &[1, 1, 1, 1, 2, 1, 1, 1, 1]);
    let palette = Palette::hard_soft_resins();
    let svg = layer_svg(&grid, &palette, 1e-3, 0);
    let doc = roxmltree::Document::parse(&svg).expect("well-formed SVG");
    let inkscape = "http://www.inkscape.org/namespaces/inkscape";
    let mut cuts = 0;
    for n in doc
        .descendants()
        .filter(|n| n.attribute("stroke").is_some())
    {
        let stroke = n.attribute("stroke").unwrap();
        let width: f64 = n.attribute("stroke-width").unwrap().parse().unwrap();
        assert!(width <= 0.0254, "{width} mm is not a hairline");
        assert_eq!(
            n.attribute("fill"),
            Some("none"),
            "a stroked {n:?} is filled"
        );
        if n.attribute("class") == Some("cut") || n.has_tag_name("circle") {
            assert_eq!(stroke, "#ff0000");
            cuts += 1;
        } else {
            assert_eq!(stroke, "#0000ff", "{n:?}");
        }
    }
    assert_eq!(cuts, 2 + 3, "two material paths and three alignment holes");
    for text in doc.descendants().filter(|n| n.has_tag_name("text")) {
        assert_eq!(text.attribute("fill"), Some("#000000"));
    }
    for (id, material) in palette.iter() {
        let layer = doc
            .descendants()
            .find(|n| n.attribute("id") == Some(&format!("material-{}", id.index())))
            .expect("a layer per material present");
        assert_eq!(
            layer.attribute((inkscape, "label")),
            Some(format!("cut {}", material.name).as_str())
        );
        assert_eq!(layer.attribute((inkscape, "groupmode")), Some("layer"));
    }
    // Material 0's path: the hole (1 mm²) before the outline (9 mm²).
    let ring = doc
        .descendants()
        .find(|n| n.attribute("data-material") == Some("0"))
        .unwrap();
    let areas: Vec<f64> = ring
        .attribute("d")
        .unwrap()
        .split('Z')
        .filter(|p| !p.trim().is_empty())
        .map(|sub| {
            let numbers: Vec<f64> = sub
                .split(|c: char| c == 'M' || c == 'L' || c.is_whitespace())
                .filter(|t| !t.is_empty())
                .map(|t| t.parse().unwrap())
                .collect();
            let points: Vec<[f64; 2]> = numbers.chunks(2).map(|c| [c[0], c[1]]).collect();
            let n = points.len();
            (0..n)
                .map(|i| {
                    let (p, q) = (points[i], points[(i + 1) % n]);
                    p[0] * q[1] - q[0] * p[1]
                })
                .sum::<f64>()
                .abs()
                / 2.0
        })
        .collect();
    assert_eq!(areas, vec![1.0, 9.0]);
}
