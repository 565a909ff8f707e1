use super::*;

#[test]
fn rotation_vector_round_trips_small_and_large_angles() {
    for theta in [
        Vec3::new(1e-7, -2e-7, 3e-8),
        Vec3::new(0.01, 0.02, -0.03),
        Vec3::new(0.5, -1.0, 2.0),
        Vec3::new(0.0, 3.0, 0.0),
    ] {
        let back = Quat::from_rotation_vector(theta).rotation_vector();
        // f64 round trip through sin/cos/atan2: 1e-12 relative is generous.
        assert!(
            (back - theta).norm() <= 1e-12 * theta.norm().max(1.0),
            "{theta:?} -> {back:?}"
        );
    }
}

#[test]
fn matrix_and_rotate_agree() {
    let q = Quat::from_rotation_vector(Vec3::new(0.3, -0.7, 1.1));
    let v = Vec3::new(1.0, 2.0, -3.0);
    let m = q.to_matrix();
    // Both are a handful of f64 operations on O(1) values.
    assert!((m.apply(v) - q.rotate(v)).norm() < 1e-14);
    assert!((m.apply_transpose(m.apply(v)) - v).norm() < 1e-14);
}

#[test]
fn axis_shift_round_trips_and_stays_right_handed() {
    let a = Vec3::new(1.0, 2.0, 3.0);
    let b = Vec3::new(-0.5, 0.25, 4.0);
    for k in 0..3 {
        assert_eq!(a.to_axis(k).unshift_axis(k), a);
        assert_eq!(a.to_axis(k).cross(b.to_axis(k)), a.cross(b).to_axis(k));
    }
}
