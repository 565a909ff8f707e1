//! The island-model cluster. The same config and seed give bit-identical final
//! populations whatever evaluates them: one process, one gRPC worker, two, two of which one is
//! killed mid-run, or workers that join late. Hostile peers get clear errors and change nothing.

use std::time::Duration;

use amorph_proto::v1::{self, task_result};
use amorph_proto::{PROTOCOL_VERSION, convert};
use amorph_tests::peer::{Peer, client, runtime};
use amorph_tests::{
    ClusterRun, TestWorker, fingerprint, run_locally, scratch_dir, small_beam_config,
};
use tonic::Code;

const EVALUATIONS: u64 = 240;
const SEED: u64 = 7;

/// The in-process run every cluster run must match, computed once per test process.
fn reference() -> String {
    static REFERENCE: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    REFERENCE
        .get_or_init(|| {
            fingerprint(&run_locally(
                &small_beam_config(&scratch_dir("cluster-reference"), EVALUATIONS, SEED),
                2,
            ))
        })
        .clone()
}

#[test]
fn one_two_and_a_killed_worker_give_the_in_process_result_bit_for_bit() {
    let expected = reference();

    let config = farewell_tolerant(small_beam_config(
        &scratch_dir("cluster-one"),
        EVALUATIONS,
        SEED,
    ));
    let run = ClusterRun::start(&config, 0, None);
    let worker = TestWorker::start(&run.url(), 1, None);
    let summary = run.join();
    assert_eq!(summary.evaluations, EVALUATIONS);
    assert_eq!(fingerprint(&summary), expected, "one worker");
    assert!(worker.join().unwrap().evaluated > 0);

    let config = farewell_tolerant(small_beam_config(
        &scratch_dir("cluster-two"),
        EVALUATIONS,
        SEED,
    ));
    let run = ClusterRun::start(&config, 0, None);
    let a = TestWorker::start(&run.url(), 1, None);
    let b = TestWorker::start(&run.url(), 1, None);
    let summary = run.join();
    assert_eq!(fingerprint(&summary), expected, "two workers");
    let (a, b) = (a.join().unwrap(), b.join().unwrap());
    assert!(
        a.evaluated > 0 && b.evaluated > 0,
        "both worked: {a:?} {b:?}"
    );

    // Kill one worker mid-run: its leases expire and go to the survivor.
    let config = farewell_tolerant(small_beam_config(
        &scratch_dir("cluster-killed"),
        EVALUATIONS,
        SEED,
    ));
    let run = ClusterRun::start(&config, 0, None);
    let survivor = TestWorker::start(&run.url(), 1, None);
    let victim = TestWorker::start(&run.url(), 2, None);
    run.wait_for_evaluations(EVALUATIONS / 3, Duration::from_secs(120));
    victim.kill();
    let summary = run.join();
    assert_eq!(summary.evaluations, EVALUATIONS);
    assert_eq!(fingerprint(&summary), expected, "a worker killed mid-run");
    assert!(survivor.join().is_ok());
}

/// `config` with a 5 s worker timeout: at the finish the coordinator serves until every worker has
/// heard, for at most the worker timeout, and on a loaded machine the small config's 0.6 s can
/// pass before a worker's next call, which then finds a closed port and fails after its retries
/// (CI saw it under load). The leases of a killed worker still expire on their own lease time.
fn farewell_tolerant(mut config: amorph_coordinator::RunConfig) -> amorph_coordinator::RunConfig {
    config.cluster.worker_timeout_ms = 5_000;
    config
}

/// A worker that connects to a run already under way finishes it, and the result is the
/// in-process one. The early worker leaves first (as on SIGTERM, handing back what it holds), so
/// the run waits for the late worker however slowly it starts.
#[test]
fn a_worker_that_connects_late_joins_the_run() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("cluster-late"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    let early = TestWorker::start(&run.url(), 1, None);
    run.wait_for_evaluations(EVALUATIONS / 4, Duration::from_secs(120));
    let early = early.stop().unwrap();
    assert!(early.evaluated > 0);
    assert!(
        run.evaluations() < EVALUATIONS,
        "the early worker left mid-run"
    );
    let late = TestWorker::start(&run.url(), 1, None);
    let summary = run.join();
    assert_eq!(fingerprint(&summary), expected);
    assert!(
        late.join().unwrap().evaluated > 0,
        "the late worker got work"
    );
}

#[test]
fn a_worker_between_two_calls_hears_that_the_run_finished() {
    // CI once saw a late worker, between two calls when the run ended, find the port closed
    // and retry for 60 s before failing. A worker that heartbeats slower than the run's last
    // moments must still be answered `run_finished`, not a closed connection.
    let config = small_beam_config(&scratch_dir("cluster-farewell"), 60, SEED);
    let run = ClusterRun::start(&config, 2, None);
    let rt = runtime();
    let heard = rt.block_on(async {
        let c = client(&run.url(), None).await;
        let mut bystander = Peer::register(&c, 1, "bystander").await.unwrap();
        for beat in 0.. {
            // Under the config's 600 ms worker timeout, so the coordinator keeps it registered.
            tokio::time::sleep(Duration::from_millis(250)).await;
            let answer = bystander
                .heartbeat(&[])
                .await
                .unwrap_or_else(|e| panic!("heartbeat {beat}: {e:?}"));
            if answer.run_finished {
                return beat;
            }
            assert!(beat < 2_000, "no end of the run after {beat} heartbeats");
        }
        unreachable!()
    });
    assert_eq!(run.join().evaluations, 60);
    assert!(heard > 0);
}

#[test]
fn embedded_local_workers_follow_the_queue_rules_bit_for_bit() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("cluster-local"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 2, None);
    assert_eq!(fingerprint(&run.join()), expected);
}

#[test]
fn a_wrong_token_or_protocol_version_is_refused_and_the_run_goes_on() {
    let config = small_beam_config(&scratch_dir("cluster-auth"), 60, SEED);
    let run = ClusterRun::start(&config, 0, Some("s3cret"));

    let intruder = TestWorker::start(&run.url(), 1, Some("guess"));
    let err = intruder.join().unwrap_err().to_string();
    assert!(err.contains("Unauthenticated"), "{err}");
    let anonymous = TestWorker::start(&run.url(), 1, None);
    let err = anonymous.join().unwrap_err().to_string();
    assert!(err.contains("Unauthenticated"), "{err}");

    let rt = runtime();
    let status = rt.block_on(async {
        let mut client = client(&run.url(), Some("s3cret")).await;
        client
            .register(v1::RegisterRequest {
                protocol_version: PROTOCOL_VERSION + 1,
                capacity: 1,
                name: "future".into(),
            })
            .await
            .unwrap_err()
    });
    assert_eq!(status.code(), Code::FailedPrecondition);
    assert!(status.message().contains("protocol version"), "{status:?}");

    let honest = TestWorker::start(&run.url(), 1, Some("s3cret"));
    let summary = run.join();
    assert_eq!(summary.evaluations, 60);
    assert!(honest.join().unwrap().evaluated == 60);
}

#[test]
fn hostile_messages_get_clear_errors_and_lose_nothing() {
    let expected = reference();
    let config = small_beam_config(&scratch_dir("cluster-hostile"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    let rt = runtime();
    rt.block_on(async {
        let c = client(&run.url(), None).await;
        let mut hostile = Peer::register(&c, 2, "hostile").await.unwrap();
        let empty = convert::outcome_to_wire(&amorph::task::Outcome::failed(
            amorph::outcome::Failure::Empty,
        ));

        // A probe's lease (long-polling until the first batch is queued) makes sure task 1
        // exists before it is reported: without it the report raced the first submit and could
        // get NOT_FOUND instead of FAILED_PRECONDITION.
        let mut probe = Peer::register(&c, 1, "probe").await.unwrap();
        let probed = probe.lease(1).await;
        assert_eq!(probed[0].task_id, 1);

        // Unknown task id; a task that exists but was never leased to us; an unknown worker.
        let s = hostile
            .report(999_999, task_result::Result::Outcome(empty.clone()))
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::NotFound, "{s:?}");
        assert!(s.message().contains("999999"), "{s:?}");
        let s = hostile
            .report(1, task_result::Result::Outcome(empty.clone()))
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::FailedPrecondition, "{s:?}");
        assert!(s.message().contains("never leased"), "{s:?}");
        let s = Peer {
            id: "w1-forged".into(),
            ..hostile.clone()
        }
        .heartbeat(&[])
        .await
        .unwrap_err();
        assert_eq!(s.code(), Code::NotFound, "{s:?}");

        // Lease two tasks, answer one with a NaN fitness and one with garbage metrics: both are
        // refused as this worker's errors and go back to the queue.
        let tasks = hostile.try_lease(2, 2000).await.unwrap();
        assert_eq!(tasks.len(), 2);
        let nan = v1::Outcome {
            result: Some(v1::outcome::Result::Evaluated(v1::Evaluated {
                fitness: f64::NAN,
                metrics_json: b"{}".to_vec(),
            })),
        };
        let garbage = v1::Outcome {
            result: Some(v1::outcome::Result::Evaluated(v1::Evaluated {
                fitness: -1.0,
                metrics_json: b"\xff\xfe".to_vec(),
            })),
        };
        let reply = hostile
            .report_all(vec![
                v1::TaskResult {
                    task_id: tasks[0].task_id,
                    result: Some(task_result::Result::Outcome(nan)),
                    wall_seconds: f64::NAN,
                },
                v1::TaskResult {
                    task_id: tasks[1].task_id,
                    result: Some(task_result::Result::Outcome(garbage)),
                    wall_seconds: 1.0,
                },
            ])
            .await
            .unwrap();
        assert_eq!(
            reply.dispositions,
            vec![v1::ReportDisposition::Rejected as i32; 2]
        );

        // An oversized message is refused by the size limit before any handler runs.
        let huge = vec![v1::TaskResult {
            task_id: tasks[0].task_id,
            result: Some(task_result::Result::Error(
                "x".repeat(amorph_proto::MAX_MESSAGE_BYTES + 1),
            )),
            wall_seconds: 0.0,
        }];
        // One defined status: the server refuses it from the length prefix, before reading it.
        let s = hostile.report_all(huge).await.unwrap_err();
        assert_eq!(s.code(), Code::OutOfRange, "{s:?}");
        assert!(s.message().contains("too large"), "{s:?}");
        // A scene that is not the run's.
        let s = hostile
            .client
            .fetch_scene(v1::FetchSceneRequest {
                worker_id: hostile.id.clone(),
                scene_id: "scene-0000".into(),
            })
            .await
            .unwrap_err();
        assert_eq!(s.code(), Code::NotFound);
    });

    // The run goes on with an honest worker and ends exactly as the reference: nothing the
    // hostile peer did changed a result or lost a task.
    let honest = TestWorker::start(&run.url(), 2, None);
    let summary = run.join();
    assert_eq!(fingerprint(&summary), expected);
    assert!(honest.join().is_ok());
}

#[test]
fn tls_with_a_token_runs_and_plain_http_is_refused() {
    let dir = scratch_dir("cluster-tls");
    let key = rcgen::generate_simple_self_signed(vec!["localhost".to_owned()]).unwrap();
    let cert_path = dir.join("cert.pem");
    let key_path = dir.join("key.pem");
    std::fs::write(&cert_path, key.cert.pem()).unwrap();
    std::fs::write(&key_path, key.signing_key.serialize_pem()).unwrap();
    let mut config = small_beam_config(&dir, 60, SEED);
    config.cluster.tls_cert = Some(cert_path.clone());
    config.cluster.tls_key = Some(key_path);
    // At the finish the coordinator serves until every worker has heard, for at most the worker
    // timeout: on a loaded machine the small config's 0.6 s can pass before the TLS worker's next
    // call, which then finds a closed port and fails after its retries.
    config.cluster.worker_timeout_ms = 5_000;

    // No local worker: the external TLS worker must do every evaluation, so the run cannot end
    // before it has connected. (With a local worker the run could finish first; the TLS worker,
    // then refused at the closed port, failed after its 60 s of retries once local workers stopped
    // holding the run open for the reaper at the finish.)
    let run = ClusterRun::start(&config, 0, Some("s3cret"));
    let mut plain = amorph_worker::WorkerOptions::new(run.url(), 1);
    plain.token = Some("s3cret".into());
    plain.give_up_after = Some(Duration::from_secs(2));
    plain.max_backoff = Duration::from_millis(200);
    let plain = TestWorker::with_options(plain);
    let mut opts = amorph_worker::WorkerOptions::new(format!("https://{}", run.addr), 1);
    opts.token = Some("s3cret".into());
    opts.ca_cert = Some(cert_path);
    opts.tls_domain = Some("localhost".into());
    opts.give_up_after = Some(Duration::from_secs(60));
    let secure = TestWorker::with_options(opts);
    let summary = run.join();
    assert_eq!(summary.evaluations, 60);
    assert!(secure.join().is_ok());
    // Plain HTTP/2 against a TLS server never gets through: the worker gives up, having done nothing.
    let err = plain.join().unwrap_err().to_string();
    assert!(err.contains("unreachable"), "{err}");
}
