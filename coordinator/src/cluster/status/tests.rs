use super::*;
use crate::ids::TaskId;
use tonic::Code;

#[test]
fn each_refusal_has_one_code_and_peer_text_is_escaped_and_capped() {
    let w = WorkerId { serial: 1, tag: 2 };
    assert_eq!(
        Status::from(QueueError::UnknownWorker(w)).code(),
        Code::NotFound
    );
    assert_eq!(
        Status::from(QueueError::UnknownTask(TaskId(9))).code(),
        Code::NotFound
    );
    let s = Status::from(QueueError::NotLeasedTo {
        task: TaskId(9),
        worker: w,
    });
    assert_eq!(s.code(), Code::FailedPrecondition);
    assert!(s.message().contains("never leased"), "{s:?}");

    let s = worker_id(&format!("\n{}", "x".repeat(1 << 20))).unwrap_err();
    assert_eq!(s.code(), Code::NotFound);
    assert!(s.message().len() < 200, "a megabyte id is not echoed back");
    assert!(!s.message().contains('\n'));
    assert_eq!(worker_id("").unwrap_err().code(), Code::NotFound);
    assert_eq!(worker_id("w1-000002").unwrap(), w);

    assert_eq!(
        protocol_version(PROTOCOL_VERSION + 1).unwrap_err().code(),
        Code::FailedPrecondition
    );
    assert!(protocol_version(PROTOCOL_VERSION).is_ok());
    assert_eq!(capacity(0).unwrap_err().code(), Code::InvalidArgument);
    assert_eq!(
        capacity(MAX_CAPACITY + 1).unwrap_err().code(),
        Code::InvalidArgument
    );
    assert_eq!(
        list_length("x", MAX_IDS_PER_CALL + 1).unwrap_err().code(),
        Code::InvalidArgument
    );
    // 80 characters kept, each escaped to at most 10 bytes (`\u{10ffff}`), plus the words.
    let s = unknown_scene(&"\u{1b}".repeat(100_000));
    assert!(s.message().len() < 1000, "{}", s.message().len());
    assert!(!s.message().contains('\u{1b}'));
}
