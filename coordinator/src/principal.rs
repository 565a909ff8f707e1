//! Who stands behind a worker. A principal is whoever holds one credential: the shared token (or,
//! on a coordinator without one, anyone who can reach it), one per-worker credential, or this
//! process itself. However many connections or registrations a principal opens, it is one voice:
//! verification asks a second principal, errors and fair shares are counted per principal, and a
//! proven lie quarantines the principal that told it.
//!
//! A registration's session secret is a MAC of its worker id and principal under a key this
//! process draws at start, so it is unguessable (256 bits), bound to the credential that
//! registered, and checked without storing it: a worker the reaper dropped can still deliver a
//! late outcome under its old id.

use std::fmt;
use std::sync::Arc;

use ring::hmac;
use ring::rand::{SecureRandom, SystemRandom};

use crate::ids::WorkerId;

#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Principal {
    /// This process: its local workers and its own evaluations. Trusted.
    Local,
    /// Every holder of the shared token, or everyone when the coordinator has no token.
    Shared,
    /// The holder of one per-worker credential (`coordinator credentials add NAME`).
    Credential(Arc<str>),
    /// The unknown claimant of an unchecked outcome an earlier coordinator process stored: any
    /// outside principal may have made it, so only this process may check it.
    EarlierSession,
}

impl Principal {
    pub fn is_local(&self) -> bool {
        matches!(self, Principal::Local)
    }

    /// Whether `checker` may make the second evaluation of a claim by `self`: a different
    /// principal, and for a claim of unknown origin this process alone.
    pub fn may_be_checked_by(&self, checker: &Principal) -> bool {
        match self {
            Principal::EarlierSession => checker.is_local(),
            claimant => claimant != checker,
        }
    }

    /// Whether a proven lie of one of its workers quarantines the whole principal. The shared
    /// principal is everyone with the token, honest workers included, so there the lie
    /// quarantines the one registration that told it.
    pub fn answers_for_its_workers(&self) -> bool {
        matches!(self, Principal::Credential(_))
    }
}

impl fmt::Display for Principal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Principal::Local => f.write_str("this coordinator"),
            Principal::Shared => f.write_str("the shared token"),
            Principal::Credential(name) => write!(f, "credential {name}"),
            Principal::EarlierSession => f.write_str("an earlier coordinator process's worker"),
        }
    }
}

/// Issues and checks session secrets.
#[derive(Debug)]
pub struct Sessions {
    key: hmac::Key,
}

impl Default for Sessions {
    fn default() -> Self {
        Self::new()
    }
}

impl Sessions {
    /// A fresh key from the operating system's random source.
    pub fn new() -> Self {
        let mut bytes = [0u8; 32];
        SystemRandom::new()
            .fill(&mut bytes)
            .expect("the operating system's random source is available");
        Self {
            key: hmac::Key::new(hmac::HMAC_SHA256, &bytes),
        }
    }

    fn message(worker: WorkerId, principal: &Principal) -> String {
        // The id's text has no space and a credential name none either, so the pair is unambiguous.
        format!("{worker} {principal:?}")
    }

    /// The secret of `worker` registered by `principal`: 64 hex digits.
    pub fn secret(&self, worker: WorkerId, principal: &Principal) -> String {
        let tag = hmac::sign(&self.key, Self::message(worker, principal).as_bytes());
        hex(tag.as_ref())
    }

    /// Whether `secret` is the one issued to `worker` for `principal` (in constant time).
    pub fn verify(&self, worker: WorkerId, principal: &Principal, secret: &str) -> bool {
        let Some(tag) = unhex(secret) else {
            return false;
        };
        hmac::verify(&self.key, Self::message(worker, principal).as_bytes(), &tag).is_ok()
    }
}

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

pub fn unhex(text: &str) -> Option<Vec<u8>> {
    if !text.len().is_multiple_of(2) || text.len() > 256 {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

#[cfg(test)]
mod tests;
