use super::*;

/// The regroupings on one instruction set: a block's memory image becomes one vector per
/// component and back.
fn regroupings_round_trip<A: Regroup>(arith: A) {
    let image3: [[f64; LANES]; 3] =
        std::array::from_fn(|v| std::array::from_fn(|j| (4 * v + j) as f64));
    let columns = arith.columns3(image3.map(|v| arith.vector(v)));
    // Memory holds x0 y0 z0 x1 …: value k is component k mod 3 of lane k / 3.
    for (c, column) in columns.iter().enumerate() {
        let expected: [f64; LANES] = std::array::from_fn(|j| (3 * j + c) as f64);
        assert_eq!(arith.to_array(*column), expected);
    }
    assert_eq!(arith.image3(columns).map(|v| arith.to_array(v)), image3);
    let image4: [[f64; LANES]; 4] =
        std::array::from_fn(|v| std::array::from_fn(|j| (4 * v + j) as f64));
    let columns = arith.columns4(image4.map(|v| arith.vector(v)));
    for (c, column) in columns.iter().enumerate() {
        let expected: [f64; LANES] = std::array::from_fn(|j| (4 * j + c) as f64);
        assert_eq!(arith.to_array(*column), expected);
    }
    assert_eq!(arith.columns4(columns).map(|v| arith.to_array(v)), image4);
}

#[test]
fn regroupings_round_trip_on_every_instruction_set() {
    regroupings_round_trip(Portable);
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = pulp::x86::V3::try_new() {
        regroupings_round_trip(avx2);
    }
}
