use super::*;
use crate::evaluator::Completion;
use amorph::outcome::Failure;

/// An evaluator whose checks answer from a fixed truth: fitness = task id.
struct Truth {
    quarantined: Vec<Claimant>,
    asked: Vec<TaskId>,
}

fn scored(fitness: f64) -> Outcome {
    Outcome::failed(Failure::Internal(format!("{fitness}")))
}

impl Evaluator for Truth {
    fn evaluate(
        &mut self,
        _: &[Task],
        _: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        unreachable!()
    }

    fn check(&mut self, claims: &[Claim]) -> Result<Vec<Verdict>, EvaluatorError> {
        Ok(claims
            .iter()
            .map(|c| {
                self.asked.push(c.task.id);
                let truth = scored(c.task.id.0 as f64);
                let agreed = truth == c.outcome;
                if !agreed {
                    self.quarantined.push(c.claimant.clone());
                }
                Verdict {
                    outcome: truth,
                    agreed,
                    checker: "truth".into(),
                    liars: if agreed {
                        vec![]
                    } else {
                        vec![c.claimant.clone()]
                    },
                }
            })
            .collect())
    }

    fn doubts_every_claim_of(&self, claimant: &Claimant) -> bool {
        self.quarantined.contains(claimant)
    }
}

#[test]
fn only_deciding_claims_are_checked_and_a_liars_other_claims_follow() {
    let claimant = |serial, name: &str| Claimant {
        worker: WorkerId { serial, tag: 7 },
        principal: Principal::Credential(name.into()),
    };
    let (honest, liar) = (claimant(1, "honest"), claimant(2, "liar"));
    let e = |task: u64, fitness: f64, claimant: Option<&Claimant>| Evaluated {
        task: TaskId(task),
        outcome: scored(fitness),
        claimant: claimant.cloned(),
    };
    // Task 1: trusted. 2: honest claim that decides. 3: honest claim that does not.
    // 4: a lie that decides. 5: a lie that does not decide, found once 4 is caught.
    let mut batch = vec![vec![
        e(1, 1.0, None),
        e(2, 2.0, Some(&honest)),
        e(3, 3.0, Some(&honest)),
        e(4, 40.0, Some(&liar)),
        e(5, 50.0, Some(&liar)),
    ]];
    let genomes = vec![vec![Genome { points: vec![] }; 5]];
    let mut truth = Truth {
        quarantined: vec![],
        asked: vec![],
    };
    let decide = |b: &[Vec<Evaluated>]| vec![b[0].iter().map(|e| e.task.0 % 2 == 0).collect()];
    let mut caught = Vec::new();
    let checks = confirm(
        &mut batch,
        &genomes,
        GridDims::new(2, 2, 2),
        &mut truth,
        &decide,
        &mut |claim, verdict| {
            caught.extend(verdict.liars.iter().map(|w| (w.clone(), claim.task.id)));
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(checks, 3);
    assert_eq!(truth.asked, [TaskId(2), TaskId(4), TaskId(5)]);
    for (i, e) in batch[0].iter().enumerate() {
        let task = i as u64 + 1;
        let expected_claimant = (task == 3).then_some(honest.clone());
        assert_eq!(e.claimant, expected_claimant, "task {task}");
        assert_eq!(e.outcome, scored(task as f64), "task {task}");
    }
    assert_eq!(caught, [(liar.clone(), TaskId(4)), (liar, TaskId(5))]);
}
