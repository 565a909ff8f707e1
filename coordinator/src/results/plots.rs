//! The progress plots of a run: the best of each island against evaluations and against wall
//! time, on the task's figure.

use std::path::Path;

use amorph::report::{PlotSpec, Series, line_plot};
use amorph::task::Figure;

use crate::search::Front;
use crate::summary::{HistoryRow, RunSummary};

/// Colours of the islands' lines, cycled past six.
const ISLAND_COLOURS: [[u8; 3]; 6] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
];

/// progress_evaluations.png and progress_wall_time.png.
pub(super) fn write_progress(
    dir: &Path,
    name: &str,
    summary: &RunSummary,
    figure: Figure,
) -> std::io::Result<()> {
    // Islands merged at a resolution switch (`resolution.merge_islands`) have lines up to it.
    let islands = (summary.history.iter())
        .map(|r| r.island as usize + 1)
        .max()
        .unwrap_or(0)
        .max(summary.populations.len());
    let plot = |x_of: &dyn Fn(&HistoryRow) -> f64, x_label: &str| {
        let series: Vec<Series> = (0..islands)
            .map(|i| Series {
                label: format!("island {i}"),
                colour: ISLAND_COLOURS[i % ISLAND_COLOURS.len()],
                markers: false,
                points: summary
                    .history
                    .iter()
                    .filter(|r| r.island as usize == i)
                    .filter_map(|r| Some([x_of(r), r.best_figure?]))
                    .collect(),
            })
            .collect();
        let spec = PlotSpec {
            title: format!("{name}: best design per island"),
            x_label: x_label.into(),
            y_label: figure.axis.into(),
            log_x: false,
            log_y: figure.log,
        };
        line_plot(&spec, &series)
            .to_png()
            .map_err(std::io::Error::other)
    };
    std::fs::write(
        dir.join("progress_evaluations.png"),
        plot(&|r| r.evaluations as f64, "EVALUATIONS")?,
    )?;
    std::fs::write(
        dir.join("progress_wall_time.png"),
        plot(&|r| r.wall_seconds, "WALL TIME (S)")?,
    )
}

/// pareto.png: the front on its first two objectives, a step per design, with the run's fittest
/// design by the task's single fitness marked beside it.
pub(super) fn write_front(dir: &Path, name: &str, front: &Front) -> std::io::Result<()> {
    let label = |k: usize| {
        let o = &front.objectives[k];
        let unit = if o.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", o.unit)
        };
        format!("{}{unit}", o.name.replace('_', " ")).to_uppercase()
    };
    let points: Vec<[f64; 2]> = (front.along_first().iter())
        .map(|(_, v)| [v[0], v[1]])
        .collect();
    let mut series = vec![Series {
        label: format!("front ({} designs)", points.len()),
        colour: ISLAND_COLOURS[0],
        markers: true,
        points,
    }];
    if let Some(fittest) = &front.fittest {
        series.push(Series {
            label: "fittest by the single fitness".into(),
            colour: ISLAND_COLOURS[1],
            markers: true,
            points: vec![[fittest[0], fittest[1]]],
        });
    }
    let more = if front.objectives.len() > 2 {
        " (first two objectives)"
    } else {
        ""
    };
    let spec = PlotSpec {
        title: format!("{name}: Pareto front{more}"),
        x_label: label(0),
        y_label: label(1),
        log_x: false,
        log_y: false,
    };
    let png = (line_plot(&spec, &series).to_png()).map_err(std::io::Error::other)?;
    std::fs::write(dir.join("pareto.png"), png)
}
