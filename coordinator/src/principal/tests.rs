use super::*;

#[test]
fn a_secret_is_bound_to_its_worker_principal_and_process() {
    let sessions = Sessions::new();
    let w1 = WorkerId { serial: 1, tag: 5 };
    let w2 = WorkerId { serial: 2, tag: 5 };
    let alice = Principal::Credential("alice".into());
    let secret = sessions.secret(w1, &alice);
    assert_eq!(secret.len(), 64, "256 bits");
    assert!(sessions.verify(w1, &alice, &secret));
    assert!(!sessions.verify(w2, &alice, &secret), "another worker's");
    assert!(
        !sessions.verify(w1, &Principal::Shared, &secret),
        "another credential's"
    );
    assert!(
        !Sessions::new().verify(w1, &alice, &secret),
        "another process's"
    );
    let mut flipped = secret.clone().into_bytes();
    flipped[0] = if flipped[0] == b'0' { b'1' } else { b'0' };
    assert!(!sessions.verify(w1, &alice, std::str::from_utf8(&flipped).unwrap()));
    assert!(!sessions.verify(w1, &alice, ""));
    assert!(!sessions.verify(w1, &alice, "zz"));
}

#[test]
fn a_claim_is_checked_by_another_principal_and_an_unknown_one_only_here() {
    let a = Principal::Credential("a".into());
    let b = Principal::Credential("b".into());
    assert!(!a.may_be_checked_by(&a));
    assert!(a.may_be_checked_by(&b));
    assert!(a.may_be_checked_by(&Principal::Local));
    assert!(Principal::Shared.may_be_checked_by(&a));
    assert!(!Principal::Shared.may_be_checked_by(&Principal::Shared));
    assert!(!Principal::EarlierSession.may_be_checked_by(&a));
    assert!(!Principal::EarlierSession.may_be_checked_by(&Principal::Shared));
    assert!(Principal::EarlierSession.may_be_checked_by(&Principal::Local));
}
