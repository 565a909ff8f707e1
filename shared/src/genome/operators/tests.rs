use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// 4,000 points in the middle of every range, so steps of 1 % of a range are never clamped.
fn centred(count: usize, limits: &GenomeLimits) -> Genome {
    let mid = |[lo, hi]: [f64; 2]| 0.5 * (lo + hi);
    Genome::new(vec![
        GaussianPoint {
            position: [0.5; 3],
            density: mid(limits.density),
            falloff: mid(limits.falloff),
            material: MaterialId(1),
        };
        count
    ])
}

#[test]
fn perturb_moves_each_parameter_by_the_documented_gaussian() {
    let limits = GenomeLimits::default();
    let (n, probability, step) = (4000, 0.3, 0.01);
    let before = centred(n, &limits);
    let mut after = before.clone();
    perturb(
        &mut after,
        &mut ChaCha8Rng::seed_from_u64(3),
        probability,
        step,
        &limits,
    );
    let moves = |f: &dyn Fn(&GaussianPoint) -> f64, range: f64| -> (f64, f64) {
        let d: Vec<f64> = after
            .points
            .iter()
            .zip(&before.points)
            .map(|(a, b)| (f(a) - f(b)) / range)
            .filter(|d| *d != 0.0)
            .collect();
        let share = d.len() as f64 / n as f64;
        let sd = (d.iter().map(|d| d * d).sum::<f64>() / d.len() as f64).sqrt();
        (share, sd)
    };
    let span = |[lo, hi]: [f64; 2]| hi - lo;
    for (name, (share, sd)) in [
        ("y", moves(&|p| p.position[1], 1.0)),
        ("density", moves(&|p| p.density, span(limits.density))),
        ("falloff", moves(&|p| p.falloff, span(limits.falloff))),
    ] {
        // Binomial share: sd sqrt(0.3 * 0.7 / 4000) = 0.0072, so 0.03 is four sigma. The
        // sample sd of ~1,200 normal steps is within 2 % of sigma at one sigma; 8 % is four.
        assert!((share - probability).abs() < 0.03, "{name}: share {share}");
        assert!((sd / step - 1.0).abs() < 0.08, "{name}: sd {sd}");
    }
    assert!(after.points.iter().all(|p| p.material == MaterialId(1)));
    assert_eq!(after.len(), n);
}

#[test]
fn perturb_clamps_to_the_ranges() {
    let limits = GenomeLimits::default();
    let mut g = centred(500, &limits);
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for _ in 0..20 {
        perturb(&mut g, &mut rng, 1.0, 0.5, &limits);
    }
    g.validate(&limits, 2)
        .expect("every parameter stays in range");
    let at_edge = g.points.iter().filter(|p| p.density == limits.density[1]);
    assert!(
        at_edge.count() > 0,
        "steps of half a range do reach the edges"
    );
}
