use super::*;

#[test]
fn worker_ids_round_trip_and_parse_strictly() {
    let id = WorkerId {
        serial: 42,
        tag: 0x00ab12,
    };
    assert_eq!(id.to_string(), "w42-00ab12");
    assert_eq!("w42-00ab12".parse(), Ok(id));
    for bad in [
        "",
        "w",
        "w42",
        "w42-",
        "42-00ab12",
        "w042-00ab12",
        "w42-ab12",
        "w42-00AB12",
        "w42-00ab12x",
        "w-00ab12",
        "w+4-00ab12",
        "w99999999999999999999-000000",
    ] {
        assert_eq!(bad.parse::<WorkerId>(), Err(()), "{bad}");
    }
}
