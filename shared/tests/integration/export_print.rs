//! Voxel-print slice stacks: sampled at the voxel centres the stack is the voxel design; at the
//! printer's pitch a Gaussian sphere prints as the sphere its field defines, every image has the
//! size and colours the pitch and palette give, and each material's printed volume differs from
//! the voxel design's only inside the voxels its boundary passes through.

use amorph::export::print::{PrintPitch, Slicer, VOID_RGBA, print_colours, write_slice_stack};
use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::task::Scene;
use amorph::task::locomotion::LocomotionScene;
use amorph::voxel::GridDims;

fn point(position: [f64; 3], density: f64, falloff: f64, material: u8) -> GaussianPoint {
    GaussianPoint {
        position,
        density,
        falloff,
        material: MaterialId(material),
    }
}

fn robot_scene() -> Scene {
    Scene::Locomotion(LocomotionScene::default())
}

/// Two materials side by side, a hole carved into them, and a small blob far from both that the
/// task's keep-the-largest-body rule discards.
fn two_material_genome() -> Genome {
    Genome::new(vec![
        point([0.35, 0.5, 0.3], 1.0, 0.15, 0),
        point([0.62, 0.45, 0.35], 1.0, 0.13, 1),
        point([0.48, 0.5, 0.3], -0.6, 0.06, 0),
        point([0.92, 0.92, 0.92], 1.0, 0.07, 0),
    ])
}

#[test]
fn at_the_voxel_pitch_the_stack_is_the_voxel_design() {
    let scene = robot_scene();
    let genome = two_material_genome();
    let dims = GridDims::new(10, 10, 10);
    let voxel_mm = 1e3 * scene.voxel_size(dims);
    let pitch = PrintPitch {
        dpi_x: 25.4 / voxel_mm,
        dpi_y: 25.4 / voxel_mm,
        layer_mm: voxel_mm,
    };
    let slicer = Slicer::new(&genome, &scene, dims, pitch).unwrap();
    assert_eq!(slicer.counts(), [10, 10, 10]);
    let design = scene.design(&genome, dims);
    let raw = amorph::voxel::voxelize(&genome, dims, 2, scene.threshold());
    assert!(
        raw.filled_count() > design.filled_count(),
        "the test genome must have a part the task discards"
    );
    assert!(design.material_counts(2).iter().all(|&c| c > 0));
    for z in 0..10 {
        let layer = slicer.layer(z);
        for y in 0..10 {
            for x in 0..10 {
                assert_eq!(
                    layer[x + 10 * y],
                    design.get(x, y, z),
                    "voxel ({x}, {y}, {z})"
                );
            }
        }
    }
}

#[test]
fn a_gaussian_sphere_prints_as_its_sphere_at_the_printer_pitch() {
    // One point of density 1 and falloff σ: the field exceeds the threshold ½ inside the radius
    // R = L σ √(2 ln 2), L the workspace's side. Every droplet must say exactly that, except within
    // a micrometre of the surface where rounding decides.
    let scene = robot_scene();
    let (sigma, centre) = (0.15, [0.5, 0.47, 0.53]);
    let genome = Genome::new(vec![point(centre, 1.0, sigma, 1)]);
    let dims = GridDims::new(10, 10, 10);
    let side_mm = 1e3 * scene.voxel_size(dims) * 10.0;
    let radius = side_mm * sigma * (2.0 * 2f64.ln()).sqrt();
    let slicer = Slicer::new(&genome, &scene, dims, PrintPitch::default()).unwrap();
    let [nx, ny, nz] = slicer.counts();
    let pitch = slicer.pitch_mm();
    let (mut filled, mut checked) = (0usize, 0usize);
    for k in 0..nz {
        let layer = slicer.layer(k);
        for j in 0..ny {
            for i in 0..nx {
                let p = [i, j, k].map(|c| c as f64 + 0.5);
                let r = (0..3)
                    .map(|a| (p[a] * pitch[a] - centre[a] * side_mm).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let cell = layer[i + nx * j];
                if (r - radius).abs() > 1e-3 {
                    assert_eq!(
                        cell,
                        (r < radius).then_some(MaterialId(1)),
                        "droplet ({i}, {j}, {k}) at {r} mm from the centre, R = {radius} mm"
                    );
                    checked += 1;
                }
                filled += usize::from(cell.is_some());
            }
        }
    }
    assert!(checked > nx * ny * nz * 99 / 100);
    // The droplet count is the sphere's volume to within the droplets the surface cuts: a shell
    // of half a droplet's diagonal on either side.
    let droplet: f64 = pitch.iter().product();
    let h = 0.5 * pitch.iter().map(|p| p * p).sum::<f64>().sqrt();
    let sphere = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let printed = filled as f64 * droplet;
    assert!(
        (printed - sphere(radius)).abs() <= sphere(radius + h) - sphere(radius - h),
        "printed {printed} mm³, sphere {} mm³",
        sphere(radius)
    );
}

#[test]
fn each_image_has_the_pitch_size_and_only_palette_colours() {
    let scene = robot_scene();
    let genome = two_material_genome();
    let dims = GridDims::new(10, 10, 10);
    let dir = std::env::temp_dir().join(format!("amorph-print-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let written = write_slice_stack(&dir, &genome, &scene, dims, PrintPitch::default()).unwrap();
    // A 20 mm cube at 600 × 300 dpi and 27 µm: 20 / (25.4 / 600) = 472.4, 20 / (25.4 / 300) =
    // 236.2, 20 / 0.027 = 740.7 droplets, each rounded up so the stack covers the design.
    let (width, height, layers) = (473, 237, 741);
    assert_eq!(written.len(), layers + 1);
    let colours = print_colours(scene.palette()).unwrap();
    let mut seen = vec![0usize; colours.len()];
    for name in &written[..layers] {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(dir.join(name)).unwrap(),
        ));
        let mut reader = decoder.read_info().unwrap();
        let mut data = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut data).unwrap();
        assert_eq!((info.width, info.height), (width, height), "{name:?}");
        assert_eq!(info.color_type, png::ColorType::Rgba);
        for pixel in data[..info.buffer_size()].chunks_exact(4) {
            if pixel != VOID_RGBA {
                let m = colours.iter().position(|c| c == pixel);
                assert!(
                    m.is_some(),
                    "{name:?} has a colour {pixel:?} outside the palette"
                );
                seen[m.unwrap()] += 1;
            }
        }
    }
    assert!(
        seen.iter().all(|&n| n > 0),
        "both materials print: {seen:?}"
    );
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join(&written[layers])).unwrap()).unwrap();
    assert_eq!(manifest["layers"], layers);
    assert_eq!(manifest["width_px"], width);
    assert_eq!(manifest["height_px"], height);
    for (m, &count) in seen.iter().enumerate() {
        assert_eq!(manifest["materials"][m]["droplets"], count);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn row_zero_of_a_slice_is_the_far_side_seen_from_above() {
    // A blob near y = 0 and x = 0 must land in the images' bottom-left corner.
    let scene = robot_scene();
    let genome = Genome::new(vec![point([0.15, 0.15, 0.5], 1.0, 0.12, 0)]);
    let dims = GridDims::new(10, 10, 10);
    let slicer = Slicer::new(&genome, &scene, dims, PrintPitch::default()).unwrap();
    let [nx, ny, nz] = slicer.counts();
    let colours = print_colours(scene.palette()).unwrap();
    let png = amorph::export::print::layer_png(&slicer.layer(nz / 2), nx, &colours).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(png))
        .read_info()
        .unwrap();
    let mut data = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut data).unwrap();
    let filled = |column: usize, row: usize| data[4 * (column + nx * row) + 3] == 255;
    assert!(filled(nx * 15 / 100, ny - 1 - ny * 15 / 100));
    assert!(!filled(nx * 15 / 100, ny * 15 / 100));
}

/// Volume of each of two materials in the voxel design at `n`³, and of the voxels next to a
/// voxel of another material or of none (where the boundary of that material can pass), in mm³.
fn voxel_volumes(scene: &Scene, genome: &Genome, n: usize) -> [(f64, f64); 2] {
    let dims = GridDims::new(n, n, n);
    let voxel = (1e3 * scene.voxel_size(dims)).powi(3);
    let design = scene.design(genome, dims);
    let counts = design.material_counts(2);
    [0, 1].map(|m| {
        let id = Some(MaterialId(m as u8));
        let n = n as isize;
        let mut boundary = 0usize;
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let here = design.get_signed(x, y, z) == id;
                    let mixed = (-1..=1).any(|dz| {
                        (-1..=1).any(|dy| {
                            (-1..=1)
                                .any(|dx| (design.get_signed(x + dx, y + dy, z + dz) == id) != here)
                        })
                    });
                    boundary += usize::from(mixed);
                }
            }
        }
        (counts[m] as f64 * voxel, boundary as f64 * voxel)
    })
}

#[test]
fn each_material_prints_the_voxel_volume_but_for_its_boundary_voxels() {
    // The print and the voxel design sample one field; with falloffs of several voxels they can
    // disagree only inside voxels a material's boundary passes through, which lie next to a voxel
    // of another material or of none. And as the voxels shrink the voxel design must converge on
    // the print.
    let scene = robot_scene();
    let genome = Genome::new(vec![
        point([0.35, 0.5, 0.4], 1.0, 0.25, 0),
        point([0.7, 0.5, 0.45], 1.0, 0.22, 1),
    ]);
    let slicer = Slicer::new(
        &genome,
        &scene,
        GridDims::new(10, 10, 10),
        PrintPitch::default(),
    )
    .unwrap();
    let droplet: f64 = slicer.pitch_mm().iter().product();
    let mut printed = [0.0f64; 2];
    for k in 0..slicer.counts()[2] {
        for m in slicer.layer(k).into_iter().flatten() {
            printed[m.index()] += droplet;
        }
    }
    let coarse = voxel_volumes(&scene, &genome, 10);
    let fine = voxel_volumes(&scene, &genome, 40);
    for m in 0..2 {
        let (voxels, boundary) = coarse[m];
        assert!(voxels > 0.0);
        assert!(
            (printed[m] - voxels).abs() <= boundary,
            "material {m}: printed {} mm³, voxels {voxels} mm³, boundary voxels {boundary} mm³",
            printed[m]
        );
        assert!(
            (printed[m] - fine[m].0).abs() <= fine[m].1,
            "material {m} at 40³: printed {} mm³, voxels {:?}",
            printed[m],
            fine[m]
        );
        assert!(
            (printed[m] - fine[m].0).abs() < 0.5 * (printed[m] - voxels).abs(),
            "material {m}: 40³ voxels ({} mm³) no closer to the print ({} mm³) than 10³ ({voxels} mm³)",
            fine[m].0,
            printed[m]
        );
    }
}

#[test]
fn a_pitch_no_printer_has_is_refused_by_name() {
    let scene = robot_scene();
    let genome = two_material_genome();
    let dims = GridDims::new(10, 10, 10);
    for (pitch, field) in [
        (
            PrintPitch {
                dpi_x: 0.0,
                ..PrintPitch::default()
            },
            "dpi_x",
        ),
        (
            PrintPitch {
                layer_mm: f64::NAN,
                ..PrintPitch::default()
            },
            "layer_mm",
        ),
        (
            PrintPitch {
                dpi_y: 1e7,
                ..PrintPitch::default()
            },
            "coarser pitch",
        ),
    ] {
        let error = Slicer::new(&genome, &scene, dims, pitch).err().unwrap();
        assert!(error.to_string().contains(field), "{error}");
    }
}
