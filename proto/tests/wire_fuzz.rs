//! Every message a peer sends goes through these decoders before anything else sees it. Driven here
//! with arbitrary bytes and with real messages whose numbers are replaced by arbitrary ones (NaN,
//! infinities, extremes, negative counts): no decoder and no plausibility check may panic, and
//! whatever they accept must be what a domain type can hold. 2,000 cases per property in CI
//! (`PROPTEST_CASES` raises it for a longer run by hand).

use amorph::genome::{GaussianPoint, Genome, GenomeLimits};
use amorph::material::MaterialId;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use amorph_proto::convert;
use amorph_proto::v1::{self, task_result};
use proptest::prelude::*;
use prost::Message;

fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -2.0..2.0f64,
        1 => any::<f64>(),
        1 => prop::sample::select(vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            0.0,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            -1.7e308,
            1e-320,
        ]),
    ]
}

fn wild_point() -> impl Strategy<Value = v1::GaussianPoint> {
    (
        wild_f64(),
        wild_f64(),
        wild_f64(),
        wild_f64(),
        wild_f64(),
        prop_oneof![0u32..3, any::<u32>()],
    )
        .prop_map(|(x, y, z, density, falloff, material)| v1::GaussianPoint {
            x,
            y,
            z,
            density,
            falloff,
            material,
        })
}

/// A real beam outcome at 4x12x4, as JSON, whose numbers the test then replaces.
fn beam_outcome() -> (Scene, serde_json::Value) {
    static ONCE: std::sync::OnceLock<(Scene, serde_json::Value)> = std::sync::OnceLock::new();
    ONCE.get_or_init(evaluate_beam).clone()
}

fn evaluate_beam() -> (Scene, serde_json::Value) {
    let scene: Scene = serde_json::from_value(serde_json::json!({
        "kind": "beam",
        "target": "circular_arc"
    }))
    .expect("a beam scene");
    let dims = GridDims::new(4, 12, 4);
    let genome = Genome::new(
        [0.05, 0.35, 0.65, 0.95]
            .iter()
            .map(|&y| GaussianPoint {
                position: [0.5, y, 0.5],
                density: 1.0,
                falloff: 0.4,
                material: MaterialId(0),
            })
            .collect(),
    );
    let outcome = scene.evaluate(&genome, dims);
    assert!(
        matches!(outcome, Outcome::Evaluated { .. }),
        "a solid block evaluates: {outcome:?}"
    );
    let json = serde_json::to_value(&outcome).expect("outcomes serialize");
    (scene, json)
}

/// Every number in `value`, in document order, as a mutable reference.
fn numbers(value: &mut serde_json::Value) -> Vec<&mut serde_json::Value> {
    match value {
        serde_json::Value::Number(_) => vec![value],
        serde_json::Value::Array(items) => items.iter_mut().flat_map(numbers).collect(),
        serde_json::Value::Object(fields) => fields.values_mut().flat_map(numbers).collect(),
        _ => Vec::new(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn arbitrary_bytes_never_panic_a_decoder(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        if let Ok(task) = v1::Task::decode(&bytes[..]) {
            if let Some(g) = &task.genome {
                let _ = convert::genome_from_wire(g);
            }
            let _ = convert::dims_from_wire(task.resolution.as_ref());
        }
        if let Ok(report) = v1::ReportRequest::decode(&bytes[..]) {
            for r in &report.results {
                if let Some(task_result::Result::Outcome(o)) = &r.result {
                    let _ = convert::outcome_from_wire(o);
                }
            }
        }
        let _ = v1::RegisterRequest::decode(&bytes[..]);
        let _ = v1::HeartbeatRequest::decode(&bytes[..]);
        let _ = convert::scene_from_wire(&bytes);
    }

    #[test]
    fn a_wire_genome_is_refused_or_valid(points in prop::collection::vec(wild_point(), 0..8)) {
        let wire = v1::Genome { points };
        if let Ok(genome) = convert::genome_from_wire(&wire) {
            for p in &genome.points {
                prop_assert!(p.position.iter().all(|v| (0.0..=1.0).contains(v)));
                prop_assert!(p.density.is_finite() && p.falloff.is_finite() && p.falloff > 0.0);
            }
            // What the coordinator hands out comes back bit for bit.
            let again = convert::genome_from_wire(&convert::genome_to_wire(&genome)).unwrap();
            prop_assert_eq!(again, genome.clone());
            // The domain's own limits then decide; they answer, never panic.
            let _ = genome.validate(&GenomeLimits::default(), 2);
        }
    }

    #[test]
    fn a_reported_outcome_with_wild_numbers_is_checked_without_panicking(
        picks in prop::collection::vec((any::<prop::sample::Index>(), wild_f64()), 1..6),
        dims in (1usize..9, 1usize..20, 1usize..9),
    ) {
        let (scene, mut json) = beam_outcome();
        {
            let mut slots = numbers(&mut json);
            for (at, value) in &picks {
                let i = at.index(slots.len());
                *slots[i] = serde_json::Number::from_f64(*value)
                    .map_or(serde_json::Value::Null, serde_json::Value::Number);
            }
        }
        // A count given a fraction no longer parses (measured: about 60 % of cases still do and
        // reach the check).
        let Ok(outcome) = serde_json::from_value::<Outcome>(json) else { return Ok(()) };
        let wire = convert::outcome_to_wire(&outcome);
        if let Ok(decoded) = convert::outcome_from_wire(&wire) {
            let dims = GridDims::new(dims.0, dims.1, dims.2);
            let _ = scene.check_outcome(&decoded, dims);
            let _ = scene.headline(&decoded);
            let _ = scene.figure(&decoded);
        }
    }
}
