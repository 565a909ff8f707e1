//! Per-worker credentials and the check every call passes before it reaches a handler.
//!
//! A credentials file (`cluster.credentials_file`) holds one line per credential,
//! `NAME SHA256-OF-TOKEN`, so the file itself gives no one a worker's token. The token a worker
//! presents is `NAME.SECRET` (64 hex digits of secret), written once, by
//! `coordinator credentials add NAME`, to a file of its own that goes to that worker alone (a
//! Kubernetes Secret, a file in a Slurm job's private directory). The shared token, when one is
//! configured, stays valid beside the credentials: all its holders are one principal.

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use ring::digest;
use ring::rand::{SecureRandom, SystemRandom};
use tonic::{Request, Status};
use tracing::warn;

use crate::principal::{Principal, hex, unhex};

/// Longest credential name.
pub const MAX_NAME_CHARS: usize = 64;

/// The credentials of a credentials file, by name.
#[derive(Clone, Debug, Default)]
pub struct Credentials {
    digests: HashMap<Arc<str>, Vec<u8>>,
}

/// Why a credentials file or a command on it was refused; the message names the file and line.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CredentialsError(String);

fn valid_name(name: &str) -> bool {
    (1..=MAX_NAME_CHARS).contains(&name.len())
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

fn sha256(text: &str) -> Vec<u8> {
    digest::digest(&digest::SHA256, text.as_bytes())
        .as_ref()
        .to_vec()
}

impl Credentials {
    /// Reads a credentials file; a bad line is refused with its file and line number.
    pub fn load(path: &Path) -> Result<Self, CredentialsError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            CredentialsError(format!("cluster.credentials_file {}: {e}", path.display()))
        })?;
        Self::parse(&text, path)
    }

    fn parse(text: &str, path: &Path) -> Result<Self, CredentialsError> {
        let mut digests = HashMap::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let at = || format!("{}:{}", path.display(), n + 1);
            let mut fields = line.split_whitespace();
            let (Some(name), Some(digest), None) = (fields.next(), fields.next(), fields.next())
            else {
                return Err(CredentialsError(format!(
                    "{}: expected `NAME SHA256` (two fields)",
                    at()
                )));
            };
            if !valid_name(name) {
                return Err(CredentialsError(format!(
                    "{}: credential name {name:?} must be 1 to {MAX_NAME_CHARS} letters, digits, '-' or '_'",
                    at()
                )));
            }
            let Some(digest) = unhex(digest).filter(|d| d.len() == 32) else {
                return Err(CredentialsError(format!(
                    "{}: the digest of {name} is not 64 hex digits",
                    at()
                )));
            };
            if digests.insert(Arc::<str>::from(name), digest).is_some() {
                return Err(CredentialsError(format!(
                    "{}: credential {name} is listed twice",
                    at()
                )));
            }
        }
        Ok(Self { digests })
    }

    pub fn len(&self) -> usize {
        self.digests.len()
    }

    pub fn is_empty(&self) -> bool {
        self.digests.is_empty()
    }

    /// The principal a presented token proves, if any. The digest comparison is in constant time
    /// (a digest, not the token, is what an attacker could learn bits of anyway).
    pub fn principal(&self, token: &str) -> Option<Principal> {
        let (name, _) = token.split_once('.')?;
        let (name, expected) = self.digests.get_key_value(name)?;
        constant_time_eq(&sha256(token), expected).then(|| Principal::Credential(name.clone()))
    }

    /// Adds credential `name` to the file at `path` (made if missing) and writes its token to
    /// `token_out`, readable by its owner alone. Returns the token.
    pub fn add(path: &Path, name: &str, token_out: &Path) -> Result<String, CredentialsError> {
        if !valid_name(name) {
            return Err(CredentialsError(format!(
                "credential name {name:?} must be 1 to {MAX_NAME_CHARS} letters, digits, '-' or '_'"
            )));
        }
        let existing = if path.exists() {
            Self::load(path)?
        } else {
            Self::default()
        };
        if existing.digests.contains_key(name) {
            return Err(CredentialsError(format!(
                "{}: credential {name} exists already (remove it first to issue a new token)",
                path.display()
            )));
        }
        let mut secret = [0u8; 32];
        SystemRandom::new()
            .fill(&mut secret)
            .map_err(|_| CredentialsError("the system's random source failed".into()))?;
        let token = format!("{name}.{}", hex(&secret));
        write_private(token_out, &format!("{token}\n"))?;
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| CredentialsError(format!("{}: {e}", path.display())))?;
        writeln!(file, "{name} {}", hex(&sha256(&token)))
            .map_err(|e| CredentialsError(format!("{}: {e}", path.display())))?;
        Ok(token)
    }

    /// Removes credential `name` from the file; a running coordinator keeps it until restarted.
    pub fn remove(path: &Path, name: &str) -> Result<(), CredentialsError> {
        let credentials = Self::load(path)?;
        if !credentials.digests.contains_key(name) {
            return Err(CredentialsError(format!(
                "{}: no credential named {name}",
                path.display()
            )));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| CredentialsError(format!("{}: {e}", path.display())))?;
        let kept: String = text
            .lines()
            .filter(|l| l.split_whitespace().next() != Some(name))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(path, kept).map_err(|e| CredentialsError(format!("{}: {e}", path.display())))
    }

    /// The names in the file, sorted.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.digests.keys().map(|n| n.to_string()).collect();
        names.sort();
        names
    }
}

/// Writes a file only its owner may read (on Unix; elsewhere the platform's default).
fn write_private(path: &Path, text: &str) -> Result<(), CredentialsError> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
    let mut file = options.open(path).map_err(|e| {
        CredentialsError(format!(
            "{}: {e} (a token file is never overwritten)",
            path.display()
        ))
    })?;
    file.write_all(text.as_bytes())
        .map_err(|e| CredentialsError(format!("{}: {e}", path.display())))
}

/// Where `credentials add NAME` writes the token when not told: `NAME.token` beside the file.
pub fn default_token_path(credentials: &Path, name: &str) -> PathBuf {
    credentials
        .parent()
        .unwrap_or(Path::new("."))
        .join(format!("{name}.token"))
}

/// Compares without an early exit, so response time does not leak how much of a guess was right.
pub(crate) fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The check in front of every call but the health check: it finds the caller's principal from
/// `authorization: Bearer …` and puts it in the request's extensions for the handler. Without a
/// shared token or credentials everyone is the shared principal.
#[derive(Clone, Debug)]
pub struct Authenticator {
    shared: Option<Arc<[u8]>>,
    credentials: Arc<Credentials>,
    /// Told which connection proved which principal (for per-credential connection limits).
    on_authenticated: Option<ConnectionHook>,
}

/// Called with each authenticated call; an error refuses the call.
pub type HookFn = dyn Fn(&Request<()>, &Principal) -> Result<(), Status> + Send + Sync;

#[derive(Clone)]
struct ConnectionHook(Arc<HookFn>);

impl std::fmt::Debug for ConnectionHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ConnectionHook")
    }
}

impl Authenticator {
    pub fn new(shared: Option<&str>, credentials: Credentials) -> Self {
        Self {
            shared: shared.map(|t| t.as_bytes().into()),
            credentials: Arc::new(credentials),
            on_authenticated: None,
        }
    }

    /// Calls `hook` with every authenticated call's request and principal; an error refuses the
    /// call.
    pub fn on_authenticated(mut self, hook: Arc<HookFn>) -> Self {
        self.on_authenticated = Some(ConnectionHook(hook));
        self
    }

    fn open(&self) -> bool {
        self.shared.is_none() && self.credentials.is_empty()
    }

    /// The principal a bearer token proves.
    pub fn principal(&self, token: Option<&[u8]>) -> Option<Principal> {
        if self.open() {
            return Some(Principal::Shared);
        }
        let token = token?;
        if let Some(shared) = &self.shared
            && constant_time_eq(token, shared)
        {
            return Some(Principal::Shared);
        }
        self.credentials.principal(std::str::from_utf8(token).ok()?)
    }
}

impl tonic::service::Interceptor for Authenticator {
    fn call(&mut self, mut request: Request<()>) -> Result<Request<()>, Status> {
        let token = request
            .metadata()
            .get(amorph_proto::AUTHORIZATION)
            .and_then(|v| v.as_bytes().strip_prefix(b"Bearer "));
        let Some(principal) = self.principal(token) else {
            warn!(peer = ?request.remote_addr(), "call without a valid token refused");
            return Err(Status::unauthenticated(
                "missing or wrong token (pass the coordinator's shared secret or this worker's credential with --token, --token-file or AMORPH_TOKEN)",
            ));
        };
        if let Some(ConnectionHook(hook)) = &self.on_authenticated {
            hook(&request, &principal)?;
        }
        request.extensions_mut().insert(principal);
        Ok(request)
    }
}

#[cfg(test)]
mod tests;
