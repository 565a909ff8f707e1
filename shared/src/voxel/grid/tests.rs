use super::*;

#[test]
fn a_neighbourhood_is_the_cells_within_one_step_on_every_axis() {
    let d = GridDims::new(4, 3, 5);
    for i in 0..d.cell_count() {
        let [x, y, z] = d.coords(i).map(|c| c as isize);
        let expected: Vec<usize> = (0..d.cell_count())
            .filter(|&j| {
                let c = d.coords(j).map(|c| c as isize);
                (c[0] - x).abs() <= 1 && (c[1] - y).abs() <= 1 && (c[2] - z).abs() <= 1
            })
            .collect();
        assert_eq!(d.neighbourhood(i).collect::<Vec<_>>(), expected, "cell {i}");
    }
    assert_eq!(d.neighbourhood(0).count(), 8);
    assert_eq!(d.neighbourhood(d.index(1, 1, 1)).count(), 27);
}

#[test]
fn index_and_coords_round_trip() {
    let d = GridDims::new(3, 4, 5);
    for i in 0..d.cell_count() {
        let [x, y, z] = d.coords(i);
        assert_eq!(d.index(x, y, z), i);
    }
}

#[test]
fn outside_cells_read_as_empty() {
    let g = VoxelGrid::filled(GridDims::new(2, 2, 2), MaterialId(0));
    assert_eq!(g.get_signed(-1, 0, 0), None);
    assert_eq!(g.get_signed(0, 2, 0), None);
    assert_eq!(g.get_signed(1, 1, 1), Some(MaterialId(0)));
}
