//! The robot's pictures: recording a walk changes nothing about it (the observed simulation is
//! bit for bit the evaluation), the GIF decodes into moving, non-blank frames in the materials'
//! colours, and the trajectory plot shows both panels.

use amorph::task::locomotion::{
    AnimationOptions, LocomotionPhase, RecordingOptions, animation_gif, record_locomotion,
    simulate_locomotion, simulate_locomotion_observed, trajectory_csv, trajectory_plot,
};

use crate::common::short_walker as walker;

#[test]
fn observing_a_walk_leaves_it_bit_identical() {
    let (genome, scene, dims) = walker();
    let body = amorph::task::design(&scene, &genome, dims);
    let dynamics = scene.dynamics_at(dims);
    let protocol = scene.protocol();
    let plain = simulate_locomotion(&body, &scene.palette, &dynamics, &protocol);
    let mut calls = 0;
    let observed = simulate_locomotion_observed(
        &body,
        &scene.palette,
        &dynamics,
        &protocol,
        7,
        &mut |_, _| calls += 1,
    );
    assert_eq!(plain, observed);
    assert!(plain.completed_fitness().is_some());
    // Settling checks every 0.01 s for 0.02 s at most, the settled call, 7 per cycle.
    assert!((1 + 3 * 7..=3 + 3 * 7).contains(&calls), "{calls} calls");
}

#[test]
fn the_recording_samples_the_centre_of_mass_densely_and_keeps_frames() {
    let (genome, scene, dims) = walker();
    let options = RecordingOptions {
        samples_per_cycle: 20,
        frame_every: 4,
    };
    let recording = record_locomotion(&genome, &scene, dims, options);
    let actuating: Vec<_> = recording
        .centre_of_mass
        .iter()
        .filter(|(s, _)| matches!(s.phase, LocomotionPhase::Actuating { .. }))
        .collect();
    assert_eq!(actuating.len(), 3 * 20);
    assert!(actuating.windows(2).all(|w| w[1].0.time > w[0].0.time));
    // Frames: the settled body, then 20 / 4 per cycle.
    assert_eq!(recording.frames.len(), 1 + 3 * 5);
    assert_eq!(recording.frames[0].phase, LocomotionPhase::Settled);
    // Every cycle's last sample is the evaluation's per-cycle centre of mass, bit for bit.
    let ends: Vec<[f64; 3]> = recording
        .centre_of_mass
        .iter()
        .filter(|(s, _)| {
            s.phase == LocomotionPhase::Settled
                || matches!(s.phase, LocomotionPhase::Actuating { sample: 20, .. })
        })
        .map(|(_, c)| *c)
        .collect();
    assert_eq!(ends, recording.outcome.centre_of_mass_trace);
    let csv = trajectory_csv(&recording);
    assert_eq!(csv.lines().count(), 1 + recording.centre_of_mass.len());
}

/// Composites a decoded GIF: each frame's opaque pixels painted over the previous picture.
fn decoded_frames(gif: &[u8]) -> (usize, usize, Vec<Vec<[u8; 3]>>) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(gif).expect("a GIF header");
    let (width, height) = (usize::from(decoder.width()), usize::from(decoder.height()));
    let mut canvas = vec![[0u8; 3]; width * height];
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().expect("a decodable frame") {
        let (left, top) = (usize::from(frame.left), usize::from(frame.top));
        for y in 0..usize::from(frame.height) {
            for x in 0..usize::from(frame.width) {
                let p = &frame.buffer[4 * (y * usize::from(frame.width) + x)..][..4];
                if p[3] != 0 {
                    canvas[(top + y) * width + left + x] = [p[0], p[1], p[2]];
                }
            }
        }
        frames.push(canvas.clone());
    }
    (width, height, frames)
}

#[test]
fn the_gif_decodes_into_moving_frames_in_the_materials_colours() {
    let (genome, scene, dims) = walker();
    let recording = record_locomotion(&genome, &scene, dims, RecordingOptions::default());
    let options = AnimationOptions::default();
    let gif = animation_gif(&recording, &scene.palette, options).unwrap();
    let (width, height, frames) = decoded_frames(&gif);
    assert_eq!(frames.len(), recording.frames.len());
    assert!(frames.len() > 1);
    assert!(width.max(height) <= options.max_side_px + 24 && width.min(height) > 50);
    let floor = [238, 238, 230];
    for (k, frame) in frames.iter().enumerate() {
        assert!(frame.contains(&floor), "frame {k} has no floor");
        // Each material's up-facing faces are drawn in its own colour, unshaded: the 6×6×6
        // body's top shows each on far more than a voxel's worth of pixels.
        for (_, material) in scene.palette.iter() {
            let shown = frame.iter().filter(|&&p| p == material.colour).count();
            assert!(shown > 40, "frame {k}: {} on {shown} px", material.name);
        }
    }
    // The body deforms and moves: frames differ from the settled one on many pixels.
    let changed = frames[1..]
        .iter()
        .map(|f| f.iter().zip(&frames[0]).filter(|(a, b)| a != b).count())
        .max()
        .unwrap();
    assert!(changed > 20, "{changed} pixels ever change");
    // Frames after the first carry only what changed: the file is far smaller than raw pixels.
    assert!(
        gif.len() < frames.len() * width * height / 4,
        "{} bytes",
        gif.len()
    );
}

#[test]
fn the_trajectory_plot_shows_the_path_in_both_panels() {
    let (genome, scene, dims) = walker();
    let recording = record_locomotion(&genome, &scene, dims, RecordingOptions::default());
    let image = trajectory_plot(&recording);
    let actuation = [31, 119, 180];
    let half = image.width * image.height / 2;
    let upper = image.pixels[..half].iter().filter(|&&p| p == actuation);
    let lower = image.pixels[half..].iter().filter(|&&p| p == actuation);
    // The line (two pixels wide) and its legend swatch in each panel.
    assert!(upper.count() > 200, "x against time panel is empty");
    assert!(lower.count() > 100, "top view panel is empty");
    let png = image.to_png().unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let reader = decoder.read_info().unwrap();
    assert_eq!(reader.info().width as usize, image.width);
}
