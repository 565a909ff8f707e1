//! The robot's centre-of-mass trajectory, from a [`LocomotionRecording`]: x against time (settling
//! then actuation, the paper's Fig. 6b) above a top view of the path on the floor, as one PNG,
//! and the samples as CSV.

use super::LocomotionPhase;
use super::recording::LocomotionRecording;
use crate::report::{Image, PlotSpec, Series, line_plot, line_plot_over};

const SETTLING: [u8; 3] = [150, 150, 150];
const ACTUATION: [u8; 3] = [31, 119, 180];
const CYCLE_END: [u8; 3] = [214, 39, 40];
/// Plot area of a [`line_plot`] (its size less the margins), for an equal-scale top view.
const PLOT_AREA_ASPECT: f64 = 430.0 / 770.0;

/// Two panels stacked: x (mm) against time (s), and the top view y (mm) against x (mm) with the
/// same scale on both axes (up to tick rounding), so a small sideways drift looks small.
pub fn trajectory_plot(recording: &LocomotionRecording) -> Image {
    let mm = |p: [f64; 3]| p.map(|c| 1e3 * c);
    let samples = &recording.centre_of_mass;
    let settling: Vec<[f64; 2]> = samples
        .iter()
        .filter(|(s, _)| !is_actuating(s.phase))
        .map(|(s, c)| [s.time, mm(*c)[0]])
        .collect();
    // The actuation line starts where settling ended, so the two join.
    let actuation: Vec<(f64, [f64; 3])> = samples
        .iter()
        .filter(|(s, _)| s.phase == LocomotionPhase::Settled || is_actuating(s.phase))
        .map(|(s, c)| (s.time, mm(*c)))
        .collect();
    let samples_per_cycle = samples
        .iter()
        .filter_map(|(s, _)| match s.phase {
            LocomotionPhase::Actuating { sample, .. } => Some(sample),
            _ => None,
        })
        .max()
        .unwrap_or(1);
    let cycle_ends: Vec<[f64; 3]> = samples
        .iter()
        .filter(|(s, _)| match s.phase {
            LocomotionPhase::Settled => true,
            LocomotionPhase::Actuating { sample, .. } => sample == samples_per_cycle,
            LocomotionPhase::Settling => false,
        })
        .map(|(_, c)| mm(*c))
        .collect();

    let against_time = line_plot(
        &PlotSpec {
            title: "CENTRE OF MASS: X AGAINST TIME".into(),
            x_label: "TIME (S)".into(),
            y_label: "X (MM)".into(),
            log_x: false,
            log_y: false,
        },
        &[
            Series {
                label: "SETTLING".into(),
                colour: SETTLING,
                points: settling,
                markers: false,
            },
            Series {
                label: "ACTUATION".into(),
                colour: ACTUATION,
                points: actuation.iter().map(|(t, c)| [*t, c[0]]).collect(),
                markers: false,
            },
        ],
    );

    let path: Vec<[f64; 2]> = actuation.iter().map(|(_, c)| [c[0], c[1]]).collect();
    let range = |a: usize| {
        path.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[a]), hi.max(p[a]))
            })
    };
    let ((x0, x1), (y0, y1)) = (range(0), range(1));
    // Widen the narrower axis to the plot area's aspect (a motionless path still gets a
    // thousandth of a voxel, so the axes have a range).
    let voxel_mm = 1e3 * recording.voxel_size;
    let width = (x1 - x0)
        .max((y1 - y0) / PLOT_AREA_ASPECT)
        .max(1e-3 * voxel_mm);
    let height = width * PLOT_AREA_ASPECT;
    let centred = |lo: f64, hi: f64, extent: f64| {
        let mid = 0.5 * (lo + hi);
        (mid - 0.5 * extent, mid + 0.5 * extent)
    };
    let top_view = if path.is_empty() {
        None
    } else {
        Some([centred(x0, x1, width), centred(y0, y1, height)])
    };
    let map = line_plot_over(
        &PlotSpec {
            title: "TOP VIEW OF THE PATH (SAME SCALE ON BOTH AXES)".into(),
            x_label: "X (MM)".into(),
            y_label: "Y (MM)".into(),
            log_x: false,
            log_y: false,
        },
        // The cycle ends first, so the path is drawn over the line joining them.
        &[
            Series {
                label: "START, END OF EACH CYCLE".into(),
                colour: CYCLE_END,
                points: cycle_ends.iter().map(|c| [c[0], c[1]]).collect(),
                markers: true,
            },
            Series {
                label: "PATH".into(),
                colour: ACTUATION,
                points: path,
                markers: false,
            },
        ],
        top_view.map_or([None, None], |[x, y]| [Some(x), Some(y)]),
    );
    stack(&against_time, &map)
}

fn is_actuating(phase: LocomotionPhase) -> bool {
    matches!(phase, LocomotionPhase::Actuating { .. })
}

/// The samples as CSV: time (s), phase, cycle, centre of mass (m).
pub fn trajectory_csv(recording: &LocomotionRecording) -> String {
    let mut csv = String::from("time_s,phase,cycle,x_m,y_m,z_m\n");
    for (s, c) in &recording.centre_of_mass {
        let (phase, cycle) = match s.phase {
            LocomotionPhase::Settling => ("settling", String::new()),
            LocomotionPhase::Settled => ("settled", String::new()),
            LocomotionPhase::Actuating { cycle, .. } => ("actuating", cycle.to_string()),
        };
        csv.push_str(&format!(
            "{},{phase},{cycle},{},{},{}\n",
            s.time, c[0], c[1], c[2]
        ));
    }
    csv
}

/// `top` above `bottom` (same width).
fn stack(top: &Image, bottom: &Image) -> Image {
    let width = top.width.max(bottom.width);
    let mut pixels = vec![[255, 255, 255]; width * (top.height + bottom.height)];
    for (row_offset, image) in [(0, top), (top.height, bottom)] {
        for y in 0..image.height {
            let row = &image.pixels[y * image.width..(y + 1) * image.width];
            pixels[(row_offset + y) * width..][..image.width].copy_from_slice(row);
        }
    }
    Image {
        width,
        height: top.height + bottom.height,
        pixels,
    }
}
