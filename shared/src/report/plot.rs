//! Line plots as PNG images with no font or system dependency: axes with 1-2-5 (or decade) ticks,
//! numeric tick labels, a title, axis labels and a legend, all drawn with a built-in 5×7 pixel
//! font (upper case, digits and the punctuation numbers need). For beam profiles, fitness
//! histories and the error-against-run-time study.

use super::render::Image;

/// One line of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub colour: [u8; 3],
    pub points: Vec<[f64; 2]>,
    /// Draw a small square at every point, not only the line.
    pub markers: bool,
}

/// What to draw around the lines.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
}

const WIDTH: usize = 900;
const HEIGHT: usize = 560;
const LEFT: f64 = 100.0;
const RIGHT: f64 = 30.0;
const TOP: f64 = 60.0;
const BOTTOM: f64 = 70.0;
const SCALE: usize = 2;
const INK: [u8; 3] = [30, 30, 30];
const GRID: [u8; 3] = [225, 225, 225];

/// Draws the series on one pair of axes. Non-finite points (and non-positive ones on a log
/// axis) are skipped.
pub fn line_plot(spec: &PlotSpec, series: &[Series]) -> Image {
    line_plot_over(spec, series, [None, None])
}

/// [`line_plot`] whose x and/or y axis covers at least the given data range (then rounded out to
/// ticks), e.g. to give both axes of a map the same scale.
pub fn line_plot_over(
    spec: &PlotSpec,
    series: &[Series],
    at_least: [Option<(f64, f64)>; 2],
) -> Image {
    let mut image = Image {
        width: WIDTH,
        height: HEIGHT,
        pixels: vec![[255, 255, 255]; WIDTH * HEIGHT],
    };
    let map = |v: f64, log: bool| if log { v.log10() } else { v };
    let usable = |p: &[f64; 2]| {
        p.iter().all(|v| v.is_finite())
            && (!spec.log_x || p[0] > 0.0)
            && (!spec.log_y || p[1] > 0.0)
    };
    let points: Vec<[f64; 2]> = series
        .iter()
        .flat_map(|s| s.points.iter().filter(|p| usable(p)))
        .map(|p| [map(p[0], spec.log_x), map(p[1], spec.log_y)])
        .collect();
    let range = |a: usize| {
        let lo = points.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
        let hi = points
            .iter()
            .map(|p| p[a])
            .fold(f64::NEG_INFINITY, f64::max);
        let log = [spec.log_x, spec.log_y][a];
        let (lo, hi) = match at_least[a] {
            Some((l, h)) => (lo.min(map(l, log)), hi.max(map(h, log))),
            None => (lo, hi),
        };
        if !lo.is_finite() {
            (0.0, 1.0)
        } else if hi - lo < 1e-12 * lo.abs().max(1e-300) {
            (lo - 0.5, hi + 0.5)
        } else {
            (lo, hi)
        }
    };
    let (x_ticks, (x0, x1)) = ticks(range(0), spec.log_x);
    let (y_ticks, (y0, y1)) = ticks(range(1), spec.log_y);
    let (pw, ph) = (WIDTH as f64 - LEFT - RIGHT, HEIGHT as f64 - TOP - BOTTOM);
    let to_px = |p: [f64; 2]| {
        [
            LEFT + (p[0] - x0) / (x1 - x0) * pw,
            TOP + ph - (p[1] - y0) / (y1 - y0) * ph,
        ]
    };

    for &t in &x_ticks {
        let [x, _] = to_px([t, y0]);
        line(&mut image, [x, TOP], [x, TOP + ph], GRID, 1);
        let label = tick_label(t, spec.log_x);
        text(
            &mut image,
            &label,
            x - text_width(&label) / 2.0,
            TOP + ph + 10.0,
            INK,
        );
    }
    for &t in &y_ticks {
        let [_, y] = to_px([x0, t]);
        line(&mut image, [LEFT, y], [LEFT + pw, y], GRID, 1);
        let label = tick_label(t, spec.log_y);
        text(
            &mut image,
            &label,
            LEFT - 10.0 - text_width(&label),
            y - 7.0,
            INK,
        );
    }
    line(&mut image, [LEFT, TOP + ph], [LEFT + pw, TOP + ph], INK, 2);
    line(&mut image, [LEFT, TOP], [LEFT, TOP + ph], INK, 2);
    text(
        &mut image,
        &spec.title,
        (WIDTH as f64 - text_width(&spec.title)) / 2.0,
        15.0,
        INK,
    );
    text(
        &mut image,
        &spec.x_label,
        LEFT + (pw - text_width(&spec.x_label)) / 2.0,
        HEIGHT as f64 - 30.0,
        INK,
    );
    text(&mut image, &spec.y_label, 10.0, TOP - 26.0, INK);

    let mut legend_rows = 0;
    for s in series {
        let pts: Vec<[f64; 2]> = s
            .points
            .iter()
            .filter(|p| usable(p))
            .map(|p| to_px([map(p[0], spec.log_x), map(p[1], spec.log_y)]))
            .collect();
        for w in pts.windows(2) {
            line(&mut image, w[0], w[1], s.colour, 2);
        }
        if s.markers || pts.len() == 1 {
            for p in &pts {
                square(&mut image, *p, 3.0, s.colour);
            }
        }
        // Legend, top right, one row per labelled series (an unlabelled one, e.g. an error bar,
        // belongs to a labelled one of its colour).
        if s.label.is_empty() {
            continue;
        }
        let y = TOP + 8.0 + 20.0 * legend_rows as f64;
        legend_rows += 1;
        let x = LEFT + pw - 16.0 - text_width(&s.label) - 30.0;
        line(&mut image, [x, y + 7.0], [x + 22.0, y + 7.0], s.colour, 3);
        text(&mut image, &s.label, x + 30.0, y, INK);
    }
    image
}

/// Tick positions (in mapped units) and the axis range they span: 1-2-5 steps, or whole decades
/// on a log axis.
fn ticks((lo, hi): (f64, f64), log: bool) -> (Vec<f64>, (f64, f64)) {
    if log {
        let (a, b) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
        let step = ((b - a) / 8.0).ceil().max(1.0);
        let ticks = (0..)
            .map(|k| a + step * f64::from(k))
            .take_while(|t| *t <= b + 1e-9)
            .collect();
        return (ticks, (a, b));
    }
    let raw = (hi - lo) / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude);
    let (a, b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    let count = ((b - a) / step).round();
    if !(a.is_finite() && b.is_finite() && (0.0..=MAX_TICKS).contains(&count)) {
        // A range near the largest f64 (any finite data must plot): seven even ticks, each
        // computed as a weighted mean so none overflows.
        let ticks = (0..=6)
            .map(|k| f64::from(k) / 6.0)
            .map(|f| lo * (1.0 - f) + hi * f)
            .collect();
        return (ticks, (lo, hi));
    }
    (
        (0..=count as i64).map(|k| a + step * k as f64).collect(),
        (a, b),
    )
}

/// More ticks than a plot can label means the range was not a plottable one.
const MAX_TICKS: f64 = 100.0;

/// Most steps a line is drawn in: a segment longer than the image runs mostly outside it, and
/// wild data must not cost unbounded time.
const MAX_LINE_STEPS: f64 = 8.0 * (WIDTH + HEIGHT) as f64;

fn tick_label(t: f64, log: bool) -> String {
    if log {
        return format!("1E{}", t.round() as i64);
    }
    if t == 0.0 {
        return "0".into();
    }
    let a = t.abs();
    if !(1e-3..1e5).contains(&a) {
        let e = a.log10().floor();
        let m = t / 10f64.powf(e);
        return format!("{}E{}", trim(format!("{m:.2}")), e as i64);
    }
    trim(format!("{t:.4}"))
}

fn trim(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn put(image: &mut Image, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as usize) < image.width && (y as usize) < image.height {
        image.pixels[y as usize * image.width + x as usize] = c;
    }
}

fn square(image: &mut Image, p: [f64; 2], half: f64, c: [u8; 3]) {
    for y in (p[1] - half).round() as i64..=(p[1] + half).round() as i64 {
        for x in (p[0] - half).round() as i64..=(p[0] + half).round() as i64 {
            put(image, x, y, c);
        }
    }
}

/// A line `thickness` pixels wide (stepped at half-pixel spacing).
pub(crate) fn line(image: &mut Image, a: [f64; 2], b: [f64; 2], c: [u8; 3], thickness: usize) {
    let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()) * 2.0)
        .ceil()
        .clamp(1.0, MAX_LINE_STEPS) as usize;
    let t = thickness as i64;
    for k in 0..=steps {
        let f = k as f64 / steps as f64;
        let (x, y) = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
        for dy in 0..t {
            for dx in 0..t {
                put(image, x as i64 + dx - t / 2, y as i64 + dy - t / 2, c);
            }
        }
    }
}

pub(crate) fn text_width(s: &str) -> f64 {
    (s.chars().count() * 6 * SCALE) as f64
}

/// Draws `s` with its top-left corner at (x, y); characters without a glyph are blank.
pub(crate) fn text(image: &mut Image, s: &str, x: f64, y: f64, c: [u8; 3]) {
    for (i, ch) in s.chars().enumerate() {
        let rows = glyph(ch.to_ascii_uppercase());
        let left = x as i64 + (i * 6 * SCALE) as i64;
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..5 {
                if bits & (0b10000 >> col) != 0 {
                    for dy in 0..SCALE {
                        for dx in 0..SCALE {
                            put(
                                image,
                                left + (col * SCALE + dx) as i64,
                                y as i64 + (r * SCALE + dy) as i64,
                                c,
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A 5×7 glyph, one row per byte, bit 4 the leftmost column.
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'A' => [14, 17, 17, 31, 17, 17, 17],
        'B' => [30, 17, 17, 30, 17, 17, 30],
        'C' => [14, 17, 16, 16, 16, 17, 14],
        'D' => [28, 18, 17, 17, 17, 18, 28],
        'E' => [31, 16, 16, 30, 16, 16, 31],
        'F' => [31, 16, 16, 30, 16, 16, 16],
        'G' => [14, 17, 16, 23, 17, 17, 15],
        'H' => [17, 17, 17, 31, 17, 17, 17],
        'I' => [14, 4, 4, 4, 4, 4, 14],
        'J' => [7, 2, 2, 2, 2, 18, 12],
        'K' => [17, 18, 20, 24, 20, 18, 17],
        'L' => [16, 16, 16, 16, 16, 16, 31],
        'M' => [17, 27, 21, 21, 17, 17, 17],
        'N' => [17, 17, 25, 21, 19, 17, 17],
        'O' => [14, 17, 17, 17, 17, 17, 14],
        'P' => [30, 17, 17, 30, 16, 16, 16],
        'Q' => [14, 17, 17, 17, 21, 18, 13],
        'R' => [30, 17, 17, 30, 20, 18, 17],
        'S' => [15, 16, 16, 14, 1, 1, 30],
        'T' => [31, 4, 4, 4, 4, 4, 4],
        'U' => [17, 17, 17, 17, 17, 17, 14],
        'V' => [17, 17, 17, 17, 17, 10, 4],
        'W' => [17, 17, 17, 21, 21, 21, 10],
        'X' => [17, 17, 10, 4, 10, 17, 17],
        'Y' => [17, 17, 17, 10, 4, 4, 4],
        'Z' => [31, 1, 2, 4, 8, 16, 31],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '%' => [24, 25, 2, 4, 8, 19, 3],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        '_' => [0, 0, 0, 0, 0, 0, 31],
        '[' => [14, 8, 8, 8, 8, 8, 14],
        ']' => [14, 2, 2, 2, 2, 2, 14],
        _ => [0; 7],
    }
}

#[cfg(test)]
mod tests;
