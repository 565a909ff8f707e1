use super::*;

#[test]
fn series_modulus_of_equal_materials_is_the_material() {
    assert_eq!(link_youngs_modulus(3.0e6, 3.0e6), 3.0e6);
}

#[test]
fn series_modulus_is_dominated_by_the_soft_side() {
    let e = link_youngs_modulus(1.0e9, 1.0e6);
    assert!((e - 2.0e6).abs() / 2.0e6 < 1e-3);
}

#[test]
fn invalid_poisson_ratio_is_named() {
    let mut m = Material::new("x", 1.0, 0.5);
    m.poisson_ratio = 0.5;
    let err = m.validate().unwrap_err().to_string();
    assert!(err.contains("poisson_ratio"), "{err}");
}
