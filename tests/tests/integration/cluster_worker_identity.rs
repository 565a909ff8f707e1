//! One principal, one vote. Each attack below was made against the coordinator before workers had
//! session secrets and per-credential counting (commit 67d24fb), and each changed the run: a
//! second registration of one token confirmed its own forgery, another worker's id was enough to
//! act in its name, three registrations failed a good design, a hoarder or a flood of
//! registrations or idle connections stopped every honest worker. Here each is made with a raw
//! gRPC client holding the shared token, while honest workers hold credentials of their own; the
//! run must end bit-identical to a clean run, with no honest worker quarantined.

use std::path::Path;
use std::time::{Duration, Instant};

use amorph_coordinator::RunConfig;
use amorph_coordinator::cluster::credentials::Credentials;
use amorph_proto::v1::{self, task_result};
use amorph_tests::peer::{Peer, client, forged, runtime, swapped};
use amorph_tests::{
    ClusterRun, TestWorker, clean_small_beam, fingerprint, run_locally, scratch_dir,
    small_beam_config,
};
use tonic::Code;

const SEED: u64 = 21;
const SHARED: &str = "the-shared-token";

/// A small beam run served with the shared token and one credential per name in `names`, whose
/// tokens are returned in order.
fn guarded(dir: &Path, evaluations: u64, names: &[&str]) -> (RunConfig, Vec<String>) {
    let mut config = small_beam_config(dir, evaluations, SEED);
    let file = dir.join("credentials");
    let tokens = names
        .iter()
        .map(|n| Credentials::add(&file, n, &dir.join(format!("{n}.token"))).unwrap())
        .collect();
    config.cluster.credentials_file = Some(file);
    (config, tokens)
}

fn is_check(task: &v1::Task) -> bool {
    task.task_id >= amorph_proto::ids::TaskId::FIRST_CHECK
}

/// Sybil: registration A reports plausible forgeries (other designs' honest outcomes) and
/// registration B, under the same token, asks for every task it can get to confirm them. B is
/// never given a check of a shared-token claim: with no other principal at work, the coordinator
/// makes every check itself, A is caught and quarantined, and the run ends as a clean run.
#[test]
fn a_second_registration_of_one_token_cannot_confirm_its_own_forgery() {
    sybil("identity-sybil", 1, false);
}

/// The same with four confirming registrations.
#[test]
fn four_registrations_of_one_token_cannot_confirm_its_forgery() {
    sybil("identity-sybil-four", 4, false);
}

/// The same with `verify = "all"`, where every outside outcome is checked.
#[test]
fn with_every_claim_checked_one_token_still_cannot_confirm_its_forgery() {
    sybil("identity-sybil-all", 1, true);
}

fn sybil(name: &str, confirmers: usize, verify_all: bool) {
    let expected = clean_small_beam(120, SEED);
    let dir = scratch_dir(name);
    let (mut config, tokens) = guarded(&dir, 120, &["honest"]);
    // The confirmers call in turn, each evaluating what it gets: under a loaded test run one can
    // be silent for longer than the small config's 0.6 s and be dropped, which is not the attack.
    config.cluster.worker_timeout_ms = 5000;
    if verify_all {
        config.cluster.verify = amorph_coordinator::cluster::Verify::All;
    }
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let honest = runtime().block_on(async {
        let c = client(&run.url(), Some(SHARED)).await;
        let mut a = Peer::register(&c, 12, "sybil-a").await.unwrap();
        let mut confirmers_ = Vec::new();
        for i in 0..confirmers {
            confirmers_.push(
                Peer::register(&c, 1024, &format!("sybil-b{i}"))
                    .await
                    .unwrap(),
            );
        }
        let held = a.lease(12).await;
        let mut truths = Vec::new();
        for task in &held {
            truths.push(a.evaluate(task).await);
        }
        for (k, task) in held.iter().enumerate() {
            let r = a
                .report(
                    task.task_id,
                    task_result::Result::Outcome(swapped(&truths, k)),
                )
                .await
                .unwrap();
            assert_eq!(r.dispositions, [v1::ReportDisposition::Accepted as i32]);
        }
        // B does the rest of the first batch honestly, so the batch completes and its claims
        // are checked; meanwhile it asks for everything, checks included. It stops once the
        // store records the quarantine: working on, it could finish the run, and the coordinator
        // would be gone before A is refused.
        let start = Instant::now();
        while !amorph_coordinator::store::RunStore::peek_verification(&run.store)
            .is_ok_and(|(_, _, quarantined)| quarantined > 0)
        {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "no quarantine within 60 s"
            );
            for b in &mut confirmers_ {
                for task in b.try_lease(1024, 100).await.unwrap() {
                    assert!(
                        !is_check(&task),
                        "a check of a shared-token claim went to the shared token"
                    );
                    let truth = b.evaluate(&task).await;
                    b.report(task.task_id, task_result::Result::Outcome(truth))
                        .await
                        .unwrap();
                }
            }
        }
        match a.try_lease(1, 0).await {
            Err(s) => assert_eq!(s.code(), Code::PermissionDenied, "{s:?}"),
            Ok(_) => panic!("the forger was not quarantined"),
        }
        TestWorker::start(&run.url(), 2, Some(&tokens[0]))
    });
    let store = run.store.clone();
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok(), "the honest worker was never refused");
    let (_, disagreed, quarantined) =
        amorph_coordinator::store::RunStore::peek_verification(&store).unwrap();
    assert!(disagreed >= 1);
    assert_eq!(quarantined, 1, "the forger alone");
}

/// Impersonation: a worker id is a name. Another registration that knows it (ids are issued in
/// order) cannot lease, report, heartbeat or hand back leases in its name without its session
/// secret, so it can neither confirm a forgery as the honest worker nor get it quarantined.
#[test]
fn another_workers_id_without_its_session_secret_is_refused() {
    let expected = clean_small_beam(120, SEED);
    let dir = scratch_dir("identity-impersonation");
    let (config, tokens) = guarded(&dir, 120, &["honest"]);
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let honest = TestWorker::start(&run.url(), 2, Some(&tokens[0]));
    run.wait_for_evaluations(1, Duration::from_secs(30));
    runtime().block_on(async {
        let c = client(&run.url(), Some(SHARED)).await;
        let mut mallory = Peer::register(&c, 4, "mallory").await.unwrap();
        // Ids are issued in order: the honest worker registered first.
        let victim_id = format!("w1-{}", mallory.id.rsplit_once('-').unwrap().1);
        assert_ne!(victim_id, mallory.id);
        let mut posing = Peer {
            id: victim_id,
            ..mallory.clone()
        };
        let unauthenticated = |r: Result<_, tonic::Status>| match r {
            Err(s) => assert_eq!(s.code(), Code::Unauthenticated, "{s:?}"),
            Ok(_) => panic!("a call in another worker's name went through"),
        };
        unauthenticated(posing.try_lease(4, 0).await.map(|_| ()));
        unauthenticated(posing.heartbeat(&[1, 2, 3]).await.map(|_| ()));
        unauthenticated(posing.release(&[1, 2, 3]).await.map(|_| ()));
        unauthenticated(
            posing
                .report(1, task_result::Result::Outcome(forged()))
                .await
                .map(|_| ()),
        );
        posing.session = String::new();
        unauthenticated(posing.try_lease(4, 0).await.map(|_| ()));
        // Its own calls still work: the refusals above cost it nothing but the attempt.
        assert!(mallory.heartbeat(&[]).await.is_ok());
    });
    assert_eq!(fingerprint(&run.join()), expected);
    let summary = honest
        .join()
        .expect("the honest worker was never quarantined");
    assert!(summary.evaluated > 0);
}

/// Three registrations of one token cannot fail a good design: the first one's errors count for
/// the token once, the task is not leased to the token again, and the others may not report a
/// task they were never leased. A worker of another credential evaluates it.
#[test]
fn several_registrations_of_one_token_cannot_fail_a_task() {
    let expected = clean_small_beam(120, SEED);
    let dir = scratch_dir("identity-errors");
    let (config, tokens) = guarded(&dir, 120, &["honest"]);
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    runtime().block_on(async {
        let c = client(&run.url(), Some(SHARED)).await;
        let mut first = Peer::register(&c, 4, "first").await.unwrap();
        let failed = first.lease(4).await;
        for task in &failed {
            first
                .report(
                    task.task_id,
                    task_result::Result::Error("out of memory".into()),
                )
                .await
                .unwrap();
        }
        for name in ["second", "third"] {
            let mut other = Peer::register(&c, 24, name).await.unwrap();
            let got = other.try_lease(24, 500).await.unwrap();
            assert!(
                got.iter()
                    .all(|t| failed.iter().all(|f| f.task_id != t.task_id)),
                "a task the token failed was leased to the token again"
            );
            let ids: Vec<u64> = got.iter().map(|t| t.task_id).collect();
            other.release(&ids).await.unwrap();
            for task in &failed {
                let s = other
                    .report(
                        task.task_id,
                        task_result::Result::Error("out of memory".into()),
                    )
                    .await
                    .unwrap_err();
                assert_eq!(s.code(), Code::FailedPrecondition, "{s:?}");
            }
        }
    });
    let honest = TestWorker::start(&run.url(), 2, Some(&tokens[0]));
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().is_ok());
}

/// Hoarding: a worker that declares capacity 1,024 and names its leases in every heartbeat, never
/// reporting, holds no more than its share while the honest worker waits, keeps what it holds
/// only for the lease lifetime (measured evaluation times, within lease_ms and max_lease_ms), and
/// what it let lapse goes to the honest worker first. The honest worker keeps storing evaluations
/// and the run ends as a clean run.
#[test]
fn a_hoarder_gets_its_share_and_loses_what_it_sits_on() {
    const EVALUATIONS: u64 = 60;
    let expected = clean_small_beam(EVALUATIONS, SEED);
    let dir = scratch_dir("identity-hoarding");
    let (mut config, tokens) = guarded(&dir, EVALUATIONS, &["honest"]);
    config.cluster.max_lease_ms = 3000;
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let honest = TestWorker::start(&run.url(), 2, Some(&tokens[0]));
    let url = run.url();
    let store = run.store.clone();
    let hoarder = std::thread::spawn(move || {
        runtime().block_on(async {
            let c = client(&url, Some(SHARED)).await;
            let mut hoarder = Peer::register(&c, 1024, "hoarder").await.unwrap();
            let mut held = std::collections::BTreeSet::new();
            let mut most = 0;
            loop {
                let Ok(got) = hoarder.try_lease(1024, 100).await else {
                    return most;
                };
                held.extend(got.iter().map(|t| t.task_id));
                let named: Vec<u64> = held.iter().copied().collect();
                let Ok(beat) = hoarder.heartbeat(&named).await else {
                    return most;
                };
                held.retain(|t| !beat.revoked_task_ids.contains(t));
                most = most.max(held.len());
                if beat.run_finished {
                    return most;
                }
            }
        })
    });
    let summary = run.join();
    assert_eq!(fingerprint(&summary), expected);
    let honest = honest.join().expect("the honest worker was never refused");
    assert!(
        honest.evaluated >= EVALUATIONS,
        "every stored evaluation is the honest worker's: {}",
        honest.evaluated
    );
    let most = hoarder.join().unwrap();
    assert!(
        most <= 256,
        "max_capacity bounds what the hoarder holds: {most}"
    );
    assert_eq!(
        amorph_coordinator::store::RunStore::peek_evaluation_count(&store).unwrap(),
        EVALUATIONS
    );
}

/// A flood of registrations under one token, kept alive by heartbeats, never shuts out a worker
/// of another credential: the token holds at most `max_workers_per_credential` registrations, and
/// a new one pushes out its longest-idle one.
#[test]
fn a_registration_flood_leaves_other_credentials_working() {
    let expected = clean_small_beam(120, SEED);
    let dir = scratch_dir("identity-flood");
    let (mut config, tokens) = guarded(&dir, 120, &["honest"]);
    config.cluster.worker_timeout_ms = 3000;
    config.cluster.max_workers_per_credential = 64;
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let flood = runtime().block_on(async {
        let c = client(&run.url(), Some(SHARED)).await;
        let mut flood = Vec::new();
        for i in 0..400 {
            flood.push(Peer::register(&c, 1, &format!("flood-{i}")).await.unwrap());
        }
        let mut evicted = 0;
        for peer in &mut flood[..400 - 64] {
            if let Err(s) = peer.heartbeat(&[]).await {
                assert_eq!(s.code(), Code::NotFound, "{s:?}");
                evicted += 1;
            }
        }
        assert_eq!(evicted, 400 - 64, "all but the newest 64 were pushed out");
        flood.split_off(400 - 64)
    });
    let url = run.url();
    let keep_alive = std::thread::spawn(move || {
        runtime().block_on(async {
            let mut flood = flood;
            loop {
                for peer in &mut flood {
                    if let Ok(beat) = peer.heartbeat(&[]).await
                        && beat.run_finished
                    {
                        return;
                    }
                }
                tokio::time::sleep(Duration::from_millis(500)).await;
                if client_gone(&url).await {
                    return;
                }
            }
        })
    });
    let honest = TestWorker::start(&run.url(), 2, Some(&tokens[0]));
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().unwrap().evaluated > 0);
    keep_alive.join().unwrap();
}

async fn client_gone(url: &str) -> bool {
    tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .is_err()
}

/// Connections that complete the HTTP/2 handshake and answer every PING but never make a call
/// cannot hold the coordinator's slots: few wait at once per address, a new one pushes out the
/// oldest, and each is closed at the handshake deadline. A worker connecting after 300 of them
/// gets in.
#[test]
fn idle_connections_cannot_keep_a_worker_out() {
    let expected = clean_small_beam(120, SEED);
    let dir = scratch_dir("identity-connections");
    let (config, tokens) = guarded(&dir, 120, &["honest"]);
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let rt = runtime();
    let idle: Vec<_> = rt.block_on(async {
        let mut idle = Vec::new();
        for _ in 0..300 {
            // Refused or pushed out ones fail here or later; either way they hold nothing.
            if let Ok(channel) = tonic::transport::Endpoint::from_shared(run.url())
                .unwrap()
                .connect()
                .await
            {
                idle.push(channel);
            }
        }
        idle
    });
    let honest = TestWorker::start(&run.url(), 2, Some(&tokens[0]));
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(honest.join().unwrap().evaluated > 0);
    drop(idle);
}

/// A checker that contradicts a hundred honest claims in one Report call costs the coordinator
/// one evaluation of its own: that one proves the checker lied, and its other verdicts count for
/// nothing and are made again elsewhere. The claimant is not quarantined.
#[test]
fn a_checker_contradicting_many_claims_costs_the_coordinator_one_evaluation() {
    let dir = scratch_dir("identity-checker");
    let (mut config, tokens) = guarded(&dir, 140, &["claimant", "third"]);
    config.search.population = 50;
    let initial = config.search.population * config.search.islands;
    let mut reference = config.clone();
    reference.results_dir = scratch_dir("identity-checker-reference");
    reference.cluster.credentials_file = None;
    let expected = fingerprint(&run_locally(&reference, 2));
    let run = ClusterRun::start(&config, 0, Some(SHARED));
    let contradicted = runtime().block_on(async {
        let mut claimant = Peer::register(
            &client(&run.url(), Some(&tokens[0])).await,
            1024,
            "claimant",
        )
        .await
        .unwrap();
        let held = claimant.lease(initial).await;
        let mut liar = Peer::register(&client(&run.url(), Some(SHARED)).await, 256, "contrarian")
            .await
            .unwrap();
        // The claimant reports the whole initial population honestly while the liar waits for
        // work, so that every check of it goes to the liar.
        let honest = async {
            tokio::time::sleep(Duration::from_millis(300)).await;
            let mut results = Vec::new();
            for task in &held {
                results.push(v1::TaskResult {
                    task_id: task.task_id,
                    result: Some(task_result::Result::Outcome(claimant.evaluate(task).await)),
                    wall_seconds: 0.0,
                });
            }
            claimant.report_all(results).await.unwrap();
        };
        let checks = async {
            let mut checks = Vec::new();
            let start = Instant::now();
            while checks.len() < initial && start.elapsed() < Duration::from_secs(20) {
                checks.extend(
                    liar.clone()
                        .try_lease(256, 500)
                        .await
                        .unwrap()
                        .into_iter()
                        .filter(is_check),
                );
            }
            checks
        };
        let ((), checks) = tokio::join!(honest, checks);
        assert_eq!(checks.len(), initial, "every initial claim is checked");
        let mut truths = Vec::new();
        for task in &checks {
            truths.push(liar.evaluate(task).await);
        }
        let results: Vec<v1::TaskResult> = (0..checks.len())
            .filter(|&k| swapped(&truths, k) != truths[k])
            .map(|k| v1::TaskResult {
                task_id: checks[k].task_id,
                result: Some(task_result::Result::Outcome(swapped(&truths, k))),
                wall_seconds: 0.0,
            })
            .collect();
        let n = results.len();
        liar.report_all(results).await.unwrap();
        n
    });
    assert!(
        contradicted >= 10,
        "only {contradicted} claims contradicted"
    );
    let third = TestWorker::start(&run.url(), 2, Some(&tokens[1]));
    let store = run.store.clone();
    assert_eq!(fingerprint(&run.join()), expected);
    assert!(third.join().is_ok());
    let db = rusqlite::Connection::open(&store).unwrap();
    let settled: i64 = db
        .query_row(
            "SELECT count(*) FROM verification WHERE checker LIKE '%then coordinator%'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(
        settled, 1,
        "the coordinator's own re-evaluations stop at the first proven lie"
    );
    let quarantined: Vec<String> = db
        .prepare("SELECT DISTINCT worker FROM quarantine")
        .unwrap()
        .query_map([], |r| r.get(0))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(quarantined.len(), 1, "{quarantined:?}");
    assert!(quarantined[0].contains("shared token"), "{quarantined:?}");
}
