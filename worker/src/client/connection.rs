//! Reaching the coordinator: the endpoint with its TLS, the token every call carries, and which
//! refusals no retry can fix.

use std::time::Duration;

use tonic::metadata::{Ascii, MetadataValue};
use tonic::service::Interceptor;
use tonic::transport::{Certificate, ClientTlsConfig, Endpoint};
use tonic::{Code, Request, Status};

use super::{ClientError, WorkerOptions};

/// Metadata every call carries: the token.
#[derive(Clone, Debug)]
pub(super) struct Auth {
    pub(super) token: Option<MetadataValue<Ascii>>,
}

impl Interceptor for Auth {
    fn call(&mut self, mut request: Request<()>) -> Result<Request<()>, Status> {
        if let Some(token) = &self.token {
            request
                .metadata_mut()
                .insert(amorph_proto::AUTHORIZATION, token.clone());
        }
        Ok(request)
    }
}

pub(super) fn endpoint(opts: &WorkerOptions) -> Result<Endpoint, ClientError> {
    let mut endpoint = Endpoint::from_shared(opts.url.clone())
        .map_err(|e| ClientError::Setup(format!("--connect {}: {e}", opts.url)))?
        .connect_timeout(Duration::from_secs(5))
        .tcp_nodelay(true)
        .http2_keep_alive_interval(Duration::from_secs(10))
        .keep_alive_timeout(Duration::from_secs(10));
    if opts.url.starts_with("https://") || opts.ca_cert.is_some() {
        let mut tls = ClientTlsConfig::new();
        if let Some(ca) = &opts.ca_cert {
            let pem = std::fs::read(ca)
                .map_err(|e| ClientError::Setup(format!("--ca {}: {e}", ca.display())))?;
            tls = tls.ca_certificate(Certificate::from_pem(pem));
        }
        if let Some(domain) = &opts.tls_domain {
            tls = tls.domain_name(domain.clone());
        }
        endpoint = endpoint
            .tls_config(tls)
            .map_err(|e| ClientError::Setup(format!("TLS for {}: {e}", opts.url)))?;
    }
    Ok(endpoint)
}

/// A refusal no retry can fix: wrong token, wrong protocol version, a request the coordinator
/// calls invalid.
pub(super) fn is_fatal(status: &Status) -> bool {
    matches!(
        status.code(),
        Code::Unauthenticated
            | Code::PermissionDenied
            | Code::FailedPrecondition
            | Code::InvalidArgument
    )
}
