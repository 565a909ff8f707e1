use super::*;

fn settings(edit: impl FnOnce(&mut ClusterSection)) -> Result<ClusterSettings, String> {
    let mut c = ClusterSection::default();
    edit(&mut c);
    ClusterSettings::try_from(&c)
}

#[test]
fn defaults_are_valid_and_become_durations() {
    let s = settings(|_| {}).unwrap();
    assert_eq!(s.rules.lease, Duration::from_secs(10));
    assert_eq!(s.rules.worker_timeout, Duration::from_secs(5));
    assert!(s.local_workers >= 1);
    assert_eq!(s.threads_per_evaluation, 1);
}

/// Threads that share an evaluation take their cores from the default count of local workers,
/// never below one worker.
#[test]
fn threads_per_evaluation_divide_the_default_local_workers() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let s = settings(|c| c.threads_per_evaluation = 2).unwrap();
    assert_eq!(s.local_workers, (cores / 2).max(1));
    let s = settings(|c| c.threads_per_evaluation = 1000).unwrap();
    assert_eq!(s.local_workers, 1);
    let s = settings(|c| {
        c.threads_per_evaluation = 2;
        c.local_workers = Some(3);
    })
    .unwrap();
    assert_eq!(s.local_workers, 3, "an explicit count is kept");
}

/// Sizes and durations out of bounds (`local_workers = 100000`, which would panic in the
/// worker pool; a lease of `u64::MAX` ms, which would panic added to an `Instant`) are each
/// refused in one line naming the key.
#[test]
fn sizes_and_durations_out_of_bounds_name_their_key() {
    type Edit = fn(&mut ClusterSection);
    let cases: [(&str, Edit); 11] = [
        ("cluster.max_capacity = 0", |c| c.max_capacity = 0),
        ("cluster.max_workers_per_credential = 5000", |c| {
            c.max_workers_per_credential = 5000
        }),
        ("cluster.local_workers = 100000", |c| {
            c.local_workers = Some(100_000)
        }),
        ("cluster.local_worker_threads = 0", |c| {
            c.local_worker_threads = 0
        }),
        ("cluster.threads_per_evaluation = 0", |c| {
            c.threads_per_evaluation = 0
        }),
        ("cluster.threads_per_evaluation = 5000", |c| {
            c.threads_per_evaluation = 5000
        }),
        ("cluster.lease_ms = 18446744073709551615", |c| {
            c.lease_ms = u64::MAX
        }),
        ("cluster.worker_timeout_ms = 5", |c| c.worker_timeout_ms = 5),
        ("cluster.heartbeat_ms = 1", |c| c.heartbeat_ms = 1),
        ("cluster.max_attempts = 0", |c| c.max_attempts = 0),
        ("cluster.listen", |c| c.listen = "nowhere".into()),
    ];
    for (expected, edit) in cases {
        let err = settings(edit).unwrap_err();
        assert!(err.starts_with(expected), "{err}");
        assert!(!err.contains('\n'));
    }
}

/// `verify` reads as written and writes back the same (the run store keeps the effective
/// config); anything else names the key.
#[test]
fn verify_is_true_false_or_all() {
    for (text, verify) in [
        ("true", Verify::Decisive),
        ("false", Verify::Off),
        ("\"all\"", Verify::All),
    ] {
        let c: ClusterSection = toml::from_str(&format!("verify = {text}")).unwrap();
        assert_eq!(c.verify, verify);
        let back: ClusterSection = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
    }
    for text in ["\"some\"", "1"] {
        let err = toml::from_str::<ClusterSection>(&format!("verify = {text}")).unwrap_err();
        assert!(err.to_string().contains("cluster.verify"), "{err}");
    }
}
