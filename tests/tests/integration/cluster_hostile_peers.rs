//! Hostile and faulty peers. Each attack is made with a raw gRPC client holding the
//! run's token against a real coordinator; the coordinator must answer with the documented
//! status, keep serving, and end the run exactly as a clean run ends.

use std::time::{Duration, Instant};

use amorph_proto::v1::{self, task_result};
use amorph_proto::{PROTOCOL_VERSION, convert};
use amorph_tests::peer::{Peer, client, forged, runtime, swapped};
use amorph_tests::{
    ClusterRun, TestWorker, clean_small_beam, fingerprint, scratch_dir, small_beam_config,
};
use tonic::Code;

const EVALUATIONS: u64 = 120;
const SEED: u64 = 12;

fn reference() -> String {
    clean_small_beam(EVALUATIONS, SEED)
}

/// An outcome is a claim checked against what the run's scene can produce. A beam profile station
/// at x = -1.7e308 (finite, so it decodes) would crash the end of the run in the plot code, and
/// again on every resume; a fitness better than the design's own profile would change the result.
/// Both are refused, the worker's task goes to another worker, and the run ends as a clean run.
#[test]
fn an_outcome_the_scene_cannot_produce_is_refused() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("hostile-implausible"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    runtime().block_on(async {
        let c = client(&run.url(), None).await;
        let mut liar = Peer::register(&c, 2, "liar").await.unwrap();
        let held = liar.lease(2).await;
        for (k, task) in held.iter().enumerate() {
            let honest = liar.evaluate(task).await;
            let Some(v1::outcome::Result::Evaluated(e)) = honest.result else {
                continue; // a failed design has no numbers to forge
            };
            let mut metrics: serde_json::Value = serde_json::from_slice(&e.metrics_json).unwrap();
            let forged = if k == 0 {
                metrics["beam"]["profile"][1][0] = serde_json::json!(-1.7e308);
                v1::Evaluated {
                    fitness: e.fitness,
                    metrics_json: serde_json::to_vec(&metrics).unwrap(),
                }
            } else {
                v1::Evaluated {
                    fitness: e.fitness / 2.0, // closer to 0: a better fit than the profile's
                    metrics_json: e.metrics_json.clone(),
                }
            };
            let r = liar
                .report(
                    task.task_id,
                    task_result::Result::Outcome(v1::Outcome {
                        result: Some(v1::outcome::Result::Evaluated(forged)),
                    }),
                )
                .await
                .unwrap();
            assert_eq!(
                r.dispositions,
                [v1::ReportDisposition::Rejected as i32],
                "task {k}"
            );
        }
    });
    let honest = TestWorker::start(&run.url(), 2, None);
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
}

/// A worker's lease lapses, the task goes back to the queue, the worker then reports late
/// (accepted). The late report is final: the task is not leased again, so a second, forged report
/// cannot replace the first (here it would take the best RMS from 1.014 % to 0.000 %).
#[test]
fn a_late_report_is_final_and_a_forged_second_one_changes_nothing() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("hostile-late"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    runtime().block_on(async {
        let c = client(&run.url(), None).await;
        let mut slow = Peer::register(&c, 4, "slow").await.unwrap();
        let held = slow.lease(4).await;
        // Silent: dropped after worker_timeout, its four leases back in the queue.
        slow.wait_until_dropped().await;
        let late = slow.evaluate(&held[0]).await;
        let r = slow
            .report(held[0].task_id, task_result::Result::Outcome(late))
            .await
            .unwrap();
        assert_eq!(r.dispositions, [v1::ReportDisposition::Accepted as i32]);

        let mut forger = Peer::register(&c, 4, "forger").await.unwrap();
        let got = forger.lease(4).await;
        assert!(
            got.iter().all(|t| t.task_id != held[0].task_id),
            "a finished task was leased again"
        );
        let s = forger
            .report(held[0].task_id, task_result::Result::Outcome(forged()))
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::FailedPrecondition, "{s:?}");
    });
    let honest = TestWorker::start(&run.url(), 2, None);
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
}

/// Errors repeated by one worker for one task (here three in one `Report`) neither fail the task
/// nor replace the design's real outcome: a task fails only after `max_attempts` different
/// workers; one worker answers a task once.
#[test]
fn one_worker_cannot_fail_a_task_by_repeating_errors() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("hostile-errors"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    runtime().block_on(async {
        let c = client(&run.url(), None).await;
        let mut liar = Peer::register(&c, 1, "liar").await.unwrap();
        let task = liar.lease(1).await.remove(0);
        let error = || v1::TaskResult {
            task_id: task.task_id,
            result: Some(task_result::Result::Error("out of memory".into())),
            wall_seconds: 0.0,
        };
        let r = liar
            .report_all(vec![error(), error(), error()])
            .await
            .unwrap();
        use v1::ReportDisposition::{Duplicate, ErrorNoted};
        assert_eq!(
            r.dispositions,
            [ErrorNoted as i32, Duplicate as i32, Duplicate as i32]
        );
        // Not leased to it again, though it has room and asks.
        let again = liar.try_lease(1, 0).await.unwrap();
        assert!(again.iter().all(|t| t.task_id != task.task_id));
    });
    let honest = TestWorker::start(&run.url(), 2, None);
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
}

/// At the cluster edge, peer strings are escaped and capped before they are repeated; an empty
/// report with no worker id, a heartbeat of another protocol version and a report for a task of an
/// earlier batch never leased to the reporter each get their status.
#[test]
fn malformed_calls_get_their_status_and_echo_nothing_raw() {
    let config = small_beam_config(&scratch_dir("hostile-malformed"), 60, SEED);
    let run = ClusterRun::start(&config, 0, None);
    runtime().block_on(async {
        let c = client(&run.url(), None).await;
        // An empty report with no worker id names no worker, so it is not answered OK.
        let s = c
            .clone()
            .report(v1::ReportRequest::default())
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::NotFound, "{s:?}");

        let megabyte = format!("w1-\n\u{1b}[31m{}", "x".repeat(1 << 20));
        let s = c
            .clone()
            .heartbeat(v1::HeartbeatRequest {
                worker_id: megabyte,
                session: String::new(),
                active_task_ids: vec![],
                protocol_version: PROTOCOL_VERSION,
            })
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::NotFound);
        assert!(
            s.message().len() < 300,
            "{} bytes echoed",
            s.message().len()
        );
        assert!(!s.message().contains(['\n', '\u{1b}']), "{s:?}");

        let mut id = Peer::register(&c, 1, "evil\nname\u{1b}[2J").await.unwrap();
        let s = c
            .clone()
            .heartbeat(v1::HeartbeatRequest {
                worker_id: id.id.clone(),
                session: id.session.clone(),
                active_task_ids: vec![],
                protocol_version: PROTOCOL_VERSION + 1,
            })
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::FailedPrecondition, "{s:?}");
        assert!(s.message().contains("protocol version"), "{s:?}");

        // A task that exists but was leased to another worker: the probe's lease makes sure
        // the batch is queued (before, the test raced the first submit and could see NOT_FOUND).
        let mut probe = Peer::register(&c, 1, "probe").await.unwrap();
        let t = probe.lease(1).await.remove(0);
        let s = id
            .report(t.task_id, task_result::Result::Outcome(forged()))
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::FailedPrecondition, "{s:?}");
        assert!(s.message().contains("never leased"), "{s:?}");
    });
    let honest = TestWorker::start(&run.url(), 2, None);
    let summary = run.join();
    assert_eq!(summary.evaluations, 60);
    assert!(honest.join().is_ok());
}

/// A failed bind leaves no `run.sqlite` behind, so a retry needs neither `--resume` nor
/// `--fresh`, and the bind error is printed once.
#[test]
fn a_failed_bind_leaves_no_run_store_and_says_why_once() {
    use amorph_coordinator::job::{JobOptions, StoreMode, run_job};
    use amorph_coordinator::store::RunStore;

    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let config = small_beam_config(&scratch_dir("hostile-bind"), 60, SEED);
    let options = JobOptions {
        store: StoreMode::New,
        listen: Some(taken.local_addr().unwrap().to_string()),
        local_workers: Some(0),
        ..JobOptions::default()
    };
    let err = run_job(&config, options).unwrap_err();
    let mut chain = err.to_string();
    let mut cause = std::error::Error::source(&err);
    while let Some(c) = cause {
        chain = format!("{chain}: {c}");
        cause = c.source();
    }
    assert!(chain.starts_with("cannot listen on 127.0.0.1:"), "{chain}");
    assert_eq!(
        chain.matches("os error").count(),
        1,
        "printed once: {chain}"
    );
    assert!(
        !RunStore::path_for(&config).exists(),
        "no store left behind"
    );
}

/// A worker with the token reports outcomes the scene *can* produce, but for other designs: each
/// task it holds gets the honest outcome of another (every number passes the plausibility check).
/// Unchecked, such an outcome would enter the population and change the run's result, so every
/// outside worker's outcome that would change a population is evaluated again elsewhere (here by
/// the coordinator itself, the only other evaluator at first); the disagreement is settled by the
/// coordinator's own evaluation, the liar is quarantined (its calls refused with PERMISSION_DENIED,
/// a row in the run store) and the run ends as a clean run.
#[test]
fn a_plausible_forged_outcome_is_checked_and_its_worker_quarantined() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("hostile-plausible"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    let honest = runtime().block_on(async {
        let c = client(&run.url(), None).await;
        let mut liar = Peer::register(&c, 12, "liar").await.unwrap();
        let held = liar.lease(12).await;
        let mut truths = Vec::new();
        for task in &held {
            truths.push(liar.evaluate(task).await);
        }
        let mut forged = 0;
        for (k, task) in held.iter().enumerate() {
            // Another design's outcome where one differs (many random designs fail alike).
            let claim = swapped(&truths, k);
            forged += usize::from(claim != truths[k]);
            let r = liar
                .report(task.task_id, task_result::Result::Outcome(claim))
                .await
                .unwrap();
            assert_eq!(r.dispositions, [v1::ReportDisposition::Accepted as i32]);
        }
        assert!(forged > 0, "the designs all score alike: nothing to forge");
        let honest = TestWorker::start(&run.url(), 2, None);
        let start = Instant::now();
        loop {
            match liar.try_lease(0, 0).await {
                Err(s) if s.code() == Code::PermissionDenied => break,
                _ => assert!(
                    start.elapsed() < Duration::from_secs(60),
                    "never quarantined"
                ),
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        honest
    });
    let store = run.store.clone();
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
    let (checks, disagreed, quarantined) =
        amorph_coordinator::store::RunStore::peek_verification(&store).unwrap();
    assert!(
        checks >= 4 && disagreed >= 1,
        "{checks} checks, {disagreed} disagreed"
    );
    assert_eq!(quarantined, 1);
    // The dashboard shows the same counts, and the liar among the workers, quarantined.
    let status = amorph_tests::http::store_status(&store);
    let v = &status["verification"];
    assert_eq!(
        (
            v["checks"].as_u64(),
            v["disagreements"].as_u64(),
            v["quarantined_workers"].as_u64()
        ),
        (Some(checks), Some(disagreed), Some(quarantined))
    );
    let caught: Vec<&serde_json::Value> = (status["workers"].as_array().unwrap().iter())
        .filter(|w| w["quarantined"] == true)
        .collect();
    assert_eq!(caught.len(), 1, "{:#}", status["workers"]);
}

/// Beyond the population: with `verify = true` a worker may still claim a *worse* outcome than the
/// truth for a child, which then loses without a check. With `cluster.verify = "all"` every outside
/// claim is checked, so a worker that is honest about the initial population (every one of which is
/// checked anyway) and then calls every child it is given a failure is caught, quarantined, and the
/// run ends as a clean run.
#[test]
fn with_verify_all_a_worse_outcome_for_a_losing_child_is_caught() {
    let expected = reference();
    let mut config = small_beam_config(&scratch_dir("hostile-verify-all"), EVALUATIONS, SEED);
    config.cluster.verify = amorph_coordinator::cluster::Verify::All;
    let initial = (config.search.population * config.search.islands) as usize;
    let run = ClusterRun::start(&config, 0, None);
    let honest = runtime().block_on(async {
        let c = client(&run.url(), None).await;
        let mut liar = Peer::register(&c, initial as u32, "liar").await.unwrap();
        for task in liar.lease(initial).await {
            let truth = liar.evaluate(&task).await;
            let r = liar
                .report(task.task_id, task_result::Result::Outcome(truth))
                .await
                .unwrap();
            assert_eq!(r.dispositions, [v1::ReportDisposition::Accepted as i32]);
        }
        // The first epoch's children: every one claimed a failure, whatever it really is.
        let children = liar.lease(4).await;
        let mut lies = 0;
        for task in &children {
            let failed = convert::outcome_to_wire(&amorph::task::Outcome::failed(
                amorph::outcome::Failure::Empty,
            ));
            lies += usize::from(liar.evaluate(task).await != failed);
            liar.report(task.task_id, task_result::Result::Outcome(failed))
                .await
                .unwrap();
        }
        assert!(lies > 0, "every child really failed: nothing was a lie");
        (TestWorker::start(&run.url(), 2, None), children.len())
    });
    let (honest, children) = honest;
    let store = run.store.clone();
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
    let (checks, disagreed, quarantined) =
        amorph_coordinator::store::RunStore::peek_verification(&store).unwrap();
    assert!(checks as usize >= initial + children, "{checks} checks");
    assert!(disagreed >= 1, "{disagreed} disagreed");
    assert_eq!(quarantined, 1);
}
