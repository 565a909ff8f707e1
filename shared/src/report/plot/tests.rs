//! The plots: legend rows, any finite data, and the ticks and their labels.

use super::*;

/// An unlabelled series (an error bar) is drawn but takes no legend row: the labelled line's
/// legend stays in the first row whether the bar is drawn before or after it, and labelling
/// the bar adds a row.
#[test]
fn an_unlabelled_series_has_no_legend_row() {
    let spec = PlotSpec {
        title: "t".into(),
        x_label: "x".into(),
        y_label: "y".into(),
        log_x: false,
        log_y: false,
    };
    // The line along the bottom and the bar at the left edge touch neither each other nor
    // the legend (top right).
    let series = |label: &str, points: Vec<[f64; 2]>| Series {
        label: label.into(),
        colour: [200, 0, 0],
        points,
        markers: true,
    };
    let line = series("a", vec![[0.0, 0.0], [1.0, 0.1]]);
    let bar = |label: &str| series(label, vec![[0.0, 0.5], [0.0, 1.0]]);
    let after = line_plot(&spec, &[line.clone(), bar("")]);
    let before = line_plot(&spec, &[bar(""), line.clone()]);
    assert!(after.pixels == before.pixels);
    let labelled = line_plot(&spec, &[line, bar("b")]);
    assert!(after.pixels != labelled.pixels);
}

/// Any finite data must plot: a profile station at x = -1.7e308 (finite, so a peer could send
/// it) must not make the tick code allocate without bound.
#[test]
fn any_finite_data_plots() {
    for points in [
        vec![[-1.7e308, 0.5], [1.0, 1.0]],
        vec![[f64::MIN, f64::MIN], [f64::MAX, f64::MAX]],
        vec![[0.0, 1e-300], [1.0, 1e300]],
    ] {
        for log_y in [false, true] {
            let spec = PlotSpec {
                title: "T".into(),
                x_label: "X".into(),
                y_label: "Y".into(),
                log_x: false,
                log_y,
            };
            let series = [Series {
                label: "S".into(),
                colour: [0, 0, 0],
                markers: true,
                points: points.clone(),
            }];
            let image = line_plot(&spec, &series);
            assert_eq!(image.pixels.len(), WIDTH * HEIGHT);
        }
    }
    let (t, (a, b)) = ticks((-1.7e308, 1.0), false);
    assert!(t.len() <= 101 && a.is_finite() && b.is_finite());
}

#[test]
fn linear_ticks_are_1_2_5_steps_covering_the_range() {
    let (t, (a, b)) = ticks((0.03, 0.97), false);
    assert_eq!((a, b), (0.0, 1.0));
    assert_eq!(t.len(), 6);
    assert!((t[1] - 0.2).abs() < 1e-12);
    let (t, (a, b)) = ticks((-3.0, 2.0), true);
    assert_eq!((a, b), (-3.0, 2.0));
    assert_eq!(t, vec![-3.0, -2.0, -1.0, 0.0, 1.0, 2.0]);
}

#[test]
fn tick_labels_are_short() {
    assert_eq!(tick_label(0.25, false), "0.25");
    assert_eq!(tick_label(20000.0, false), "20000");
    assert_eq!(tick_label(2e-5, false), "2E-5");
    assert_eq!(tick_label(-3.0, true), "1E-3");
}
