use super::*;

fn diverged(reason: DivergenceReason) -> Failure {
    Failure::Diverged { reason, time: 0.25 }
}

#[test]
fn a_divergence_round_trips_through_json_typed() {
    for reason in [
        DivergenceReason::NonFinite,
        DivergenceReason::Strain {
            strain: 1.000_000_000_000_000_2,
            limit: 1.0,
        },
        DivergenceReason::Runaway {
            travel: 0.312_345_678_9,
            limit: 0.25,
        },
    ] {
        let failure = diverged(reason);
        let json = serde_json::to_value(&failure).unwrap();
        assert!(json["diverged"]["reason"].is_object(), "{json}");
        assert_eq!(serde_json::from_value::<Failure>(json).unwrap(), failure);
    }
}

/// A store written while the reason was a sentence reads back as the typed reason its sentence
/// printed: the sentence is the typed reason's own Display, so parsing inverts it exactly for
/// values with at most three decimals.
#[test]
fn a_stored_sentence_reads_as_the_reason_it_printed() {
    for reason in [
        DivergenceReason::NonFinite,
        DivergenceReason::Strain {
            strain: 1.25,
            limit: 1.0,
        },
        DivergenceReason::Runaway {
            travel: 0.375,
            limit: 0.25,
        },
    ] {
        let stored = serde_json::json!({"diverged": {"reason": reason.to_string(), "time": 0.25}});
        assert_eq!(
            serde_json::from_value::<Failure>(stored).unwrap(),
            diverged(reason)
        );
    }
    let unknown = serde_json::json!({"diverged": {"reason": "energy", "time": 0.25}});
    let err = serde_json::from_value::<Failure>(unknown)
        .unwrap_err()
        .to_string();
    assert!(err.contains("\"energy\""), "{err}");
}
