use super::*;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("amorph-credentials-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn an_added_credential_proves_its_principal_and_nothing_else() {
    let dir = scratch("add");
    let file = dir.join("credentials");
    let a = Credentials::add(&file, "node-a", &dir.join("a.token")).unwrap();
    let b = Credentials::add(&file, "node-b", &dir.join("b.token")).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.join("a.token")).unwrap().trim(),
        a
    );
    let stored = std::fs::read_to_string(&file).unwrap();
    assert!(
        !stored.contains(a.split_once('.').unwrap().1),
        "the file holds digests only"
    );
    let auth = Authenticator::new(Some("shared secret"), Credentials::load(&file).unwrap());
    let named = |n: &str| Some(Principal::Credential(n.into()));
    assert_eq!(auth.principal(Some(a.as_bytes())), named("node-a"));
    assert_eq!(auth.principal(Some(b.as_bytes())), named("node-b"));
    assert_eq!(
        auth.principal(Some(b"shared secret")),
        Some(Principal::Shared)
    );
    // Another credential's secret under this name, a truncated token, none at all.
    let forged = format!("node-a.{}", b.split_once('.').unwrap().1);
    assert_eq!(auth.principal(Some(forged.as_bytes())), None);
    assert_eq!(auth.principal(Some(&a.as_bytes()[..a.len() - 1])), None);
    assert_eq!(auth.principal(None), None);
    assert!(Credentials::add(&file, "node-a", &dir.join("a2.token")).is_err());
    assert!(
        Credentials::add(&file, "node-c", &dir.join("a.token")).is_err(),
        "a token file is never overwritten"
    );
    Credentials::remove(&file, "node-a").unwrap();
    let auth = Authenticator::new(None, Credentials::load(&file).unwrap());
    assert_eq!(auth.principal(Some(a.as_bytes())), None, "removed");
    assert_eq!(
        auth.principal(Some(b"shared secret")),
        None,
        "no shared token"
    );
    assert_eq!(auth.principal(Some(b.as_bytes())), named("node-b"));
}

#[test]
fn a_bad_line_is_refused_with_its_file_and_line() {
    let path = Path::new("creds");
    let digest = "ab".repeat(32);
    for (text, expect) in [
        (
            format!("# c\n\nx {digest} extra\n"),
            "creds:3: expected `NAME SHA256`",
        ),
        (format!("bad.name {digest}\n"), "creds:1: credential name"),
        ("x 12\n".to_string(), "creds:1: the digest of x"),
        (
            format!("x {digest}\nx {digest}\n"),
            "creds:2: credential x is listed twice",
        ),
    ] {
        let e = Credentials::parse(&text, path).unwrap_err().to_string();
        assert!(e.starts_with(expect), "{e}");
    }
    assert!(
        Authenticator::new(None, Credentials::default()).principal(None) == Some(Principal::Shared)
    );
}
