use super::*;
use crate::ids::TaskId;

fn locomotion_config(dir: &Path, seed: u64) -> RunConfig {
    let text = format!(
        "name = \"resume-schema\"\nseed = {seed}\nresults_dir = {:?}\n\n[budget]\nevaluations = 100\n\n\
         [resolution]\nlevels = [[4, 4, 4]]\n\n[scene]\nkind = \"locomotion\"\n",
        dir.display().to_string()
    );
    RunConfig::parse(&text, Path::new("resume-schema.toml")).expect("valid config")
}

/// A store written before a key existed (here `scene.dynamics.poisson`, whose default is the
/// old behaviour) resumes; a real change still does not.
#[test]
fn resume_reads_the_stored_config_with_todays_defaults() {
    let dir = std::env::temp_dir().join(format!("amorph-store-{}", std::process::id()));
    let config = locomotion_config(&dir, 1);
    let store = RunStore::create(&config, true).unwrap();
    let old_text: String = config_text(&config)
        .lines()
        .filter(|line| !line.starts_with("poisson ="))
        .map(|line| format!("{line}\n"))
        .collect();
    assert_ne!(
        old_text,
        config_text(&config),
        "the key must be in today's config"
    );
    store
        .with(|c| {
            c.execute(
                "UPDATE run SET value = ?1 WHERE key = 'config'",
                [&old_text],
            )?;
            Ok(())
        })
        .unwrap();
    drop(store);
    RunStore::resume(&config).expect("an added key with its old default resumes");
    match RunStore::resume(&locomotion_config(&dir, 2)) {
        Err(StoreError::ConfigChanged { differs, .. }) => assert_eq!(differs, "seed"),
        other => panic!("a changed seed must not resume: {:?}", other.map(|_| ())),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A corrupt population row (a negative or out-of-range island, a negative task id, as an edited
/// store may hold) is an error naming the table and the row, not a panic.
#[test]
fn a_corrupt_population_row_is_an_error_naming_it() {
    let dir = std::env::temp_dir().join(format!("amorph-store-corrupt-{}", std::process::id()));
    let store = RunStore::create(&locomotion_config(&dir, 1), true).unwrap();
    let insert = |island: i64, task: i64| {
        store
            .with(|c| {
                c.execute(
                    "INSERT INTO population(epoch, island, slot, task_id, fitness) VALUES (0, ?1, 0, ?2, 0.0)",
                    [island, task],
                )
            })
            .unwrap();
    };
    insert(0, 1);
    assert_eq!(store.population(0).unwrap(), [[TaskId(1)]]);
    for (island, task) in [(-1, 2), (1 << 40, 3), (1, -4)] {
        insert(island, task);
        let err = store.population(0).unwrap_err().to_string();
        assert!(err.contains("table population, row (epoch 0"), "{err}");
        assert!(err.contains(&format!("task_id {task}")), "{err}");
        store
            .with(|c| c.execute("DELETE FROM population WHERE task_id = ?1", [task]))
            .unwrap();
    }
    store
        .with(|c| {
            c.execute(
                "INSERT INTO evaluation(task_id, epoch, island, purpose, resolution, genome, outcome, fitness, worker, wall_seconds, finished_unix) VALUES (-7, 0, 0, 'child', '', '{}', '{}', 0.0, '', 0.0, 0)",
                [],
            )
        })
        .unwrap();
    let err = store.evaluations().unwrap_err().to_string();
    assert!(err.contains("table evaluation, row task_id -7"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
