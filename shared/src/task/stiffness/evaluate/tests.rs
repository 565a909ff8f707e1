use super::*;

#[test]
fn flanges_fill_the_outer_rows_first_and_alternate() {
    let rows = flange_rows(7, 3, 6);
    // Three in the top row (5.5), three in the bottom (0.5), the seventh in the next top row.
    let mut sorted = rows.clone();
    sorted.sort_by(f64::total_cmp);
    assert_eq!(sorted, vec![0.5, 0.5, 0.5, 4.5, 5.5, 5.5, 5.5]);
    // A full section packs every row.
    assert_eq!(flange_rows(18, 3, 6).len(), 18);
}

#[test]
fn the_second_moment_of_a_solid_section_is_h_cubed_over_12() {
    // nz rows of one cell: I = nz³/12 (unit width), exactly, by the parallel-axis sum.
    for nz in 1..10 {
        let rows: Vec<f64> = (0..nz).map(|z| z as f64 + 0.5).collect();
        let expected = (nz as f64).powi(3) / 12.0;
        assert!((second_moment(&rows) - expected).abs() < 1e-12 * expected);
    }
}
