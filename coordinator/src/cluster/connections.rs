//! Limits on the connections a peer may hold, applied before TLS and HTTP/2 see a byte: at most
//! [`MAX_CONNECTIONS`] at once (the default file limit is 1,024, and SQLite, the workers'
//! threads and the log need some), at most [`MAX_PER_ADDRESS`] from one IP address, and a
//! connection that sends nothing for [`IDLE_TIMEOUT`] is closed. A connection over a limit is
//! closed at once, so it never waits in the kernel's backlog holding a descriptor.
//!
//! An honest worker holds one connection and sends a heartbeat every `heartbeat_ms` (and the
//! server pings every 10 s), so none of this touches it; 1,100 idle TCP connections, which made
//! the coordinator unreachable for as long as they stayed open, now cost it at most 256
//! descriptors for 30 s.

use std::collections::HashMap;
use std::io;
use std::net::IpAddr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;
use tokio::time::{Instant, Sleep};
use tonic::transport::server::{Connected, TcpConnectInfo};
use tracing::warn;

pub const MAX_CONNECTIONS: usize = 256;
pub const MAX_PER_ADDRESS: usize = 64;
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(30);

/// Counts open connections, in all and per address.
#[derive(Debug, Default)]
pub struct ConnectionLimits {
    open: Mutex<(usize, HashMap<IpAddr, usize>)>,
}

impl ConnectionLimits {
    /// Admits `stream` if both limits allow; the returned stream gives its place back when it
    /// closes. `None`: refused (and logged), the stream is dropped (closed) by the caller.
    pub fn admit(self: &Arc<Self>, stream: TcpStream, idle: Duration) -> Option<LimitedStream> {
        let ip = stream.peer_addr().ok()?.ip();
        let mut open = self.open.lock().unwrap_or_else(|e| e.into_inner());
        let from_ip = open.1.get(&ip).copied().unwrap_or(0);
        if open.0 >= MAX_CONNECTIONS || from_ip >= MAX_PER_ADDRESS {
            let total = open.0;
            drop(open);
            warn!(peer = %ip, open = total, from_peer = from_ip, "connection refused: too many open");
            return None;
        }
        open.0 += 1;
        *open.1.entry(ip).or_insert(0) += 1;
        drop(open);
        Some(LimitedStream {
            stream,
            ip,
            limits: self.clone(),
            idle,
            deadline: Box::pin(tokio::time::sleep(idle)),
        })
    }

    pub fn open(&self) -> usize {
        self.open.lock().unwrap_or_else(|e| e.into_inner()).0
    }
}

/// A TCP stream holding one place in the limits; reading fails with `TimedOut` once the peer has
/// sent nothing for the idle timeout, which makes the server close it.
#[derive(Debug)]
pub struct LimitedStream {
    stream: TcpStream,
    ip: IpAddr,
    limits: Arc<ConnectionLimits>,
    idle: Duration,
    deadline: Pin<Box<Sleep>>,
}

impl Drop for LimitedStream {
    fn drop(&mut self) {
        let mut open = self.limits.open.lock().unwrap_or_else(|e| e.into_inner());
        open.0 -= 1;
        if let Some(n) = open.1.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                open.1.remove(&self.ip);
            }
        }
    }
}

impl AsyncRead for LimitedStream {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        match Pin::new(&mut self.stream).poll_read(cx, buf) {
            Poll::Ready(result) => {
                if buf.filled().len() > before {
                    let next = Instant::now() + self.idle;
                    self.deadline.as_mut().reset(next);
                }
                Poll::Ready(result)
            }
            Poll::Pending => match self.deadline.as_mut().poll(cx) {
                Poll::Ready(()) => Poll::Ready(Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "peer idle for too long",
                ))),
                Poll::Pending => Poll::Pending,
            },
        }
    }
}

impl AsyncWrite for LimitedStream {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.stream).poll_write(cx, buf)
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_shutdown(cx)
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.stream).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.stream.is_write_vectored()
    }
}

impl Connected for LimitedStream {
    type ConnectInfo = TcpConnectInfo;

    fn connect_info(&self) -> TcpConnectInfo {
        self.stream.connect_info()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::AsyncReadExt;
    use tokio::net::TcpListener;

    async fn pair(listener: &TcpListener) -> (TcpStream, TcpStream) {
        let client = TcpStream::connect(listener.local_addr().unwrap());
        let (client, server) = tokio::join!(client, listener.accept());
        (client.unwrap(), server.unwrap().0)
    }

    /// A peer cannot hold the coordinator's descriptors for as long as it likes: over the
    /// per-address limit a connection is refused; an idle one times out; closing one gives its
    /// place back.
    #[tokio::test]
    async fn regression_connections_are_limited_and_idle_ones_time_out() {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let limits = Arc::new(ConnectionLimits::default());
        let mut held = Vec::new();
        for _ in 0..MAX_PER_ADDRESS {
            let (client, server) = pair(&listener).await;
            held.push((
                client,
                limits.admit(server, IDLE_TIMEOUT).expect("under the limit"),
            ));
        }
        let (_client, server) = pair(&listener).await;
        assert!(
            limits.admit(server, IDLE_TIMEOUT).is_none(),
            "over the per-address limit"
        );
        assert_eq!(limits.open(), MAX_PER_ADDRESS);
        held.pop();
        assert_eq!(
            limits.open(),
            MAX_PER_ADDRESS - 1,
            "a closed connection gives its place back"
        );

        // A short timeout of its own, so the test waits a tenth of a second, not 30.
        let (_client, server) = pair(&listener).await;
        let mut idle = limits.admit(server, Duration::from_millis(100)).unwrap();
        let mut byte = [0u8; 1];
        let err = idle.read(&mut byte).await.unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::TimedOut);
    }
}
