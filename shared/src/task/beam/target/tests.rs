use super::*;

#[test]
fn every_profile_runs_from_clamp_to_unit_tip() {
    for p in NamedProfile::ALL {
        assert!(p.deflection(0.0).abs() < 1e-15, "{p:?}");
        assert!((p.deflection(1.0) - 1.0).abs() < 1e-12, "{p:?}");
    }
}

#[test]
fn the_polynomial_curves_upward_in_mid_span() {
    let f = |t: f64| NamedProfile::Polynomial4.deflection(t);
    let h = 1e-3;
    let curvature = |t: f64| (f(t + h) - 2.0 * f(t) + f(t - h)) / (h * h);
    assert!(curvature(0.5) < -0.4 && curvature(0.2) > 0.0 && curvature(0.8) > 0.0);
    // ...while still deflecting downward monotonically.
    assert!((1..100).all(|i| f(i as f64 / 100.0) > f((i - 1) as f64 / 100.0)));
}
