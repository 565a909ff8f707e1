//! The dashboard's JSON and pictures: what `/api/status` says of a run agrees with the files the
//! run wrote (history.csv, the island pictures, the evaluation count), live and from the store;
//! beyond loopback every request must carry the run's token.

use std::collections::{BTreeSet, HashMap};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

use amorph_coordinator::job::{JobOptions, StoreMode, run_job};
use amorph_coordinator::store::RunStore;
use amorph_tests::http::{get, serve_store};
use amorph_tests::{TestWorker, scratch_dir, small_beam_config};
use serde_json::Value;

fn status(addr: SocketAddr) -> Value {
    let (code, headers, body) = get(addr, "/api/status", &[]);
    assert_eq!(code, 200, "{}", String::from_utf8_lossy(&body));
    assert_eq!(headers["content-type"], "application/json");
    serde_json::from_slice(&body).expect("the status is JSON")
}

/// history.csv's rows as maps from column to text.
fn history_csv(run_dir: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(run_dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .map(|h| h.to_string())
                .zip(l.split(',').map(str::to_owned))
                .collect()
        })
        .collect()
}

fn number(text: &str) -> Option<f64> {
    (!text.is_empty()).then(|| text.parse().expect("a number"))
}

#[test]
fn the_status_of_a_run_agrees_with_its_files_live_and_from_the_store() {
    let dir = scratch_dir("dashboard");
    let config = small_beam_config(&dir, 160, 3);
    let (listening, heard_listening) = std::sync::mpsc::channel();
    let (tx, rx) = std::sync::mpsc::channel();
    let options = JobOptions {
        store: StoreMode::Fresh,
        listen: Some("127.0.0.1:0".into()),
        local_workers: Some(0),
        on_listening: Some(listening),
        dashboard: Some("127.0.0.1:0".into()),
        on_dashboard: Some(tx),
        ..JobOptions::default()
    };
    let cfg = config.clone();
    let job = std::thread::spawn(move || run_job(&cfg, options));
    let grpc = heard_listening
        .recv_timeout(Duration::from_secs(60))
        .expect("the coordinator listens");
    let addr = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the dashboard is served");

    // Live, before any worker came: the first batch waits in the queue. The dashboard is served
    // before the search has queued its first batch, so wait for the queue to fill.
    let deadline = Instant::now() + Duration::from_secs(60);
    let waiting = loop {
        let s = status(addr);
        if s["queue"]["queued"].as_u64().unwrap() > 0 {
            break s;
        }
        assert_eq!(s["progress"]["evaluations"], 0, "{s:#}");
        assert!(
            Instant::now() < deadline,
            "the first batch was never queued: {s:#}"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(waiting["live"], true);
    assert_eq!(waiting["run"]["task"], "beam");
    assert_eq!(waiting["run"]["budget_evaluations"], 160);
    assert_eq!(waiting["progress"]["evaluations"], 0);
    assert!(waiting["history"].as_array().unwrap().is_empty());
    assert!(waiting["best"].is_null());
    assert!(waiting["workers"].as_array().unwrap().is_empty());
    // A worker joins: the queue's view lists it with its threads before it has finished an
    // evaluation, and the store's rows count what it finished.
    let worker = TestWorker::start(&format!("http://{grpc}"), 1, None);
    let (live, registered) = loop {
        let live = status(addr);
        let workers = live["workers"].as_array().unwrap().clone();
        if let Some(w) = workers.iter().find(|w| w["registered"].is_object()) {
            break (live, w.clone());
        }
        assert!(
            !job.is_finished(),
            "the run ended before its worker was seen: {live:#}"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(registered["registered"]["threads"], 1);
    assert_eq!(registered["registered"]["trusted"], false);
    assert!(
        registered["label"]
            .as_str()
            .unwrap()
            .contains(" @127.0.0.1:"),
        "{registered:#}"
    );
    let (code, headers, page) = get(addr, "/", &[]);
    assert_eq!(code, 200);
    assert!(headers["content-type"].starts_with("text/html"));
    assert!(String::from_utf8(page).unwrap().contains("app.js"));
    assert_eq!(get(addr, "/app.js", &[]).0, 200);
    assert_eq!(get(addr, "/no-such-page", &[]).0, 404);

    let summary = job.join().unwrap().expect("the run completes");
    worker.join().expect("the worker ends with the run");
    assert!(
        TcpStream::connect_timeout(&addr, Duration::from_secs(1)).is_err(),
        "the dashboard stops with the run"
    );

    // From the store: every history.csv row, with its values.
    let store = RunStore::path_for(&config);
    let (runtime, served) = serve_store(&store, "127.0.0.1:0", None);
    let served = served.expect("the store's dashboard is served");
    let s = status(served.addr);
    assert_eq!(s["live"], false);
    assert!(s["queue"].is_null());
    let rows = history_csv(&config.run_dir());
    let history = s["history"].as_array().unwrap();
    assert_eq!(history.len(), rows.len());
    for (point, row) in history.iter().zip(&rows) {
        for (key, column) in [
            ("epoch", "epoch"),
            ("evaluations", "evaluations"),
            ("island", "island"),
            ("best_fitness", "best_fitness"),
            ("best_figure", "best_rms_percent"),
            ("mean_fitness", "mean_fitness"),
            ("replacements", "replacements"),
            ("wall_seconds", "wall_seconds"),
        ] {
            let expected = number(&row[column]);
            let got = point[key].as_f64();
            // history.csv prints numbers in their shortest round-trip form, so they agree to the
            // bit, except the wall time, printed to the millisecond.
            let tolerance = if key == "wall_seconds" { 5e-4 } else { 0.0 };
            match (expected, got) {
                (Some(e), Some(g)) => assert!(
                    (e - g).abs() <= tolerance,
                    "{key}: history.csv {e}, status {g} (epoch {}, island {})",
                    row["epoch"],
                    row["island"]
                ),
                (e, g) => assert_eq!(e, g, "{key} at epoch {}", row["epoch"]),
            }
        }
    }
    // Every evaluation is counted, and each under the worker that made it.
    assert_eq!(s["progress"]["evaluations"], summary.evaluations);
    let by_workers: u64 = (s["workers"].as_array().unwrap().iter())
        .map(|w| w["evaluations"].as_u64().unwrap())
        .sum();
    assert_eq!(by_workers, summary.evaluations);
    // The best design is the run's, and its picture is the one the report drew of its island.
    let best = &s["best"];
    assert_eq!(best["fitness"].as_f64(), summary.best().outcome.fitness());
    assert_eq!(best["task_id"].as_u64(), Some(summary.best().task.0));
    assert!(best["outcome"]["evaluated"]["metrics"]["beam"]["profile"].is_array());
    let (code, headers, png) = get(
        served.addr,
        &format!("/api/design.png?task={}", best["task_id"]),
        &[],
    );
    assert_eq!(code, 200);
    assert_eq!(headers["content-type"], "image/png");
    let island = best["island"].as_u64().unwrap();
    let drawn = std::fs::read(config.run_dir().join(format!("island-{island}-best.png"))).unwrap();
    assert!(
        png == drawn,
        "the design's picture differs from the report's"
    );
    assert_eq!(
        get(served.addr, "/api/design.png?task=999999999", &[]).0,
        404
    );
    assert_eq!(get(served.addr, "/api/design.png", &[]).0, 400);
    runtime.block_on(served.shutdown());

    // The reference documents every field the two statuses hold, and nothing else.
    let documented = documented_fields();
    let sections: BTreeSet<String> = documented.iter().map(|(p, _)| p.clone()).collect();
    let mut served_fields = BTreeSet::new();
    for status in [&live, &s] {
        json_fields(status, "", &sections, &mut served_fields);
    }
    let undocumented: Vec<_> = served_fields.difference(&documented).collect();
    let unserved: Vec<_> = documented.difference(&served_fields).collect();
    assert!(
        undocumented.is_empty(),
        "served but not in docs/reference/dashboard.md: {undocumented:?}"
    );
    assert!(
        unserved.is_empty(),
        "in docs/reference/dashboard.md but never served: {unserved:?}"
    );
}

/// (section, field) of every row of the reference's field tables: the section is a dotted path,
/// `[]` marking an array's items (`workers[].registered`), empty for the top level.
fn documented_fields() -> BTreeSet<(String, String)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/reference/dashboard.md");
    let text = std::fs::read_to_string(path).unwrap();
    let mut fields = BTreeSet::new();
    let mut section = None;
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("### ") {
            section = Some(if heading == "top level" {
                String::new()
            } else {
                heading.trim_matches('`').to_owned()
            });
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if let Some(section) = &section
            && cells.len() == 5
            && cells[1].starts_with('`')
        {
            fields.insert((section.clone(), cells[1].trim_matches('`').to_owned()));
        }
    }
    fields
}

/// (section, field) of `value`'s fields, descending into the sections the reference has.
fn json_fields(
    value: &Value,
    path: &str,
    sections: &BTreeSet<String>,
    out: &mut BTreeSet<(String, String)>,
) {
    let Some(object) = value.as_object() else {
        return;
    };
    for (key, child) in object {
        out.insert((path.to_owned(), key.clone()));
        let mut inner = if path.is_empty() {
            key.clone()
        } else {
            format!("{path}.{key}")
        };
        let items: Vec<&Value> = match child {
            Value::Array(items) => {
                inner.push_str("[]");
                items.iter().collect()
            }
            other => vec![other],
        };
        if sections.contains(&inner) {
            for item in items {
                json_fields(item, &inner, sections, out);
            }
        }
    }
}

#[test]
fn beyond_loopback_every_request_needs_the_runs_token() {
    let dir = scratch_dir("dashboard-token");
    let config = small_beam_config(&dir, 24, 1);
    amorph_tests::run_locally(&config, 2);
    let store = RunStore::path_for(&config);

    // No token to ask for: it refuses to listen beyond loopback at all.
    let (_runtime, refused) = serve_store(&store, "0.0.0.0:0", None);
    let e = refused.expect_err("no token, no dashboard beyond loopback");
    assert!(e.to_string().contains("AMORPH_TOKEN"), "{e}");

    let (runtime, served) = serve_store(&store, "0.0.0.0:0", Some("s3cret-token"));
    let served = served.expect("served with a token");
    let addr = SocketAddr::from(([127, 0, 0, 1], served.addr.port()));
    for path in ["/", "/app.js", "/api/status", "/api/design.png?task=0"] {
        assert_eq!(get(addr, path, &[]).0, 401, "{path} without the token");
        assert_eq!(
            get(addr, path, &[("Authorization", "Bearer s3cret-tokem")]).0,
            401,
            "{path} with a wrong token"
        );
    }
    assert_eq!(
        get(
            addr,
            "/api/status",
            &[("Authorization", "Bearer s3cret-token")]
        )
        .0,
        200
    );
    assert_eq!(get(addr, "/?token=s3cret-token", &[]).0, 200);
    assert_eq!(get(addr, "/api/status?token=s3cret-token", &[]).0, 200);
    runtime.block_on(served.shutdown());

    // On loopback the page is this machine's own: no token asked.
    let (runtime, served) = serve_store(&store, "127.0.0.1:0", Some("s3cret-token"));
    let served = served.unwrap();
    assert_eq!(get(served.addr, "/api/status", &[]).0, 200);
    runtime.block_on(served.shutdown());
}

#[test]
fn a_file_that_is_not_a_run_store_is_named() {
    let dir = scratch_dir("dashboard-bad-store");
    let missing = dir.join("run.sqlite");
    let (_rt, served) = serve_store(&missing, "127.0.0.1:0", None);
    let e = served.expect_err("no store").to_string();
    assert!(e.contains(&missing.display().to_string()), "{e}");
    let junk = dir.join("junk.sqlite");
    std::fs::write(&junk, "not a database").unwrap();
    let (_rt, served) = serve_store(&junk, "127.0.0.1:0", None);
    let e = served.expect_err("junk").to_string();
    assert!(e.contains("junk.sqlite"), "{e}");
}
