use super::*;

#[test]
fn grids_inside_the_limits_pass_and_overflowing_ones_name_the_count() {
    assert_eq!(checked_grid([12, 40, 12]), Ok(GridDims::new(12, 40, 12)));
    assert!(checked_grid([64, 256, 64]).is_ok(), "exactly 1 Mi voxels");
    assert_eq!(
        checked_grid([1, 1 << 32, 1 << 32]),
        Err(GridSizeError::Axis {
            axis: "ny",
            count: 1 << 32
        })
    );
    assert!(matches!(
        checked_grid([1024, 1024, 8]),
        Err(GridSizeError::Total {
            total: 8_388_608,
            ..
        })
    ));
    assert!(matches!(
        checked_grid([0, 1, 1]),
        Err(GridSizeError::Axis { axis: "nx", .. })
    ));
    assert!(matches!(
        checked_grid([u64::MAX, u64::MAX, u64::MAX]),
        Err(GridSizeError::Axis { .. })
    ));
}
