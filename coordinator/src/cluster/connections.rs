//! Limits on the connections peers may hold, applied before TLS and HTTP/2 see a byte, and
//! counted by who a connection proves to be:
//! - at most [`MAX_CONNECTIONS`] at once (the default file limit is 1,024, and SQLite, the
//!   workers' threads and the log need some) and [`MAX_PER_ADDRESS`] from one IP address;
//! - a connection that has not made an authenticated call within [`HANDSHAKE_TIMEOUT`] is
//!   closed, whether it answers the server's PINGs or not; at most [`MAX_PENDING`] such
//!   connections wait at once ([`MAX_PENDING_PER_ADDRESS`] per address), and a new one pushes
//!   out the oldest, so connections that never authenticate cannot keep a worker out;
//! - once authenticated, a connection counts against its principal, at most
//!   [`ConnectionLimits::per_principal`] each, so one credential cannot hold every slot;
//! - a connection that sends nothing for the idle timeout is closed.
//!
//! A connection over a limit is closed at once, so it never waits in the kernel's backlog holding
//! a descriptor. An honest worker holds one connection, authenticates on its first call and sends
//! a heartbeat every `heartbeat_ms`, so none of this touches it.

use std::collections::{BTreeMap, HashMap};
use std::io;
use std::net::{IpAddr, SocketAddr};
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Context, Poll, Waker};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;
use tokio::time::{Instant, Sleep};
use tonic::Status;
use tonic::transport::server::{Connected, TcpConnectInfo};
use tracing::warn;

use crate::principal::Principal;

pub const MAX_CONNECTIONS: usize = 512;
pub const MAX_PER_ADDRESS: usize = 64;
pub const MAX_PENDING: usize = 64;
pub const MAX_PENDING_PER_ADDRESS: usize = 16;
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(30);
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);

/// One admitted connection, shared by its stream and the table.
#[derive(Debug)]
struct Conn {
    ip: IpAddr,
    /// Order of admission, to push out the oldest waiting connection first.
    serial: u64,
    authenticated: AtomicBool,
    /// Pushed out of the waiting connections: the next read fails.
    evicted: AtomicBool,
    waker: Mutex<Option<Waker>>,
}

impl Conn {
    fn evict(&self) {
        self.evicted.store(true, Ordering::Release);
        if let Some(w) = self.waker.lock().unwrap_or_else(|e| e.into_inner()).take() {
            w.wake();
        }
    }
}

#[derive(Debug, Default)]
struct Table {
    per_ip: HashMap<IpAddr, (usize, usize)>,
    by_addr: HashMap<SocketAddr, (Arc<Conn>, Option<Principal>)>,
    /// Connections not yet authenticated, by admission order.
    pending: BTreeMap<u64, SocketAddr>,
    per_principal: HashMap<Principal, usize>,
    next_serial: u64,
}

/// Counts open connections, in all, per address, waiting and per principal.
#[derive(Debug)]
pub struct ConnectionLimits {
    table: Mutex<Table>,
    per_principal: usize,
}

impl Default for ConnectionLimits {
    fn default() -> Self {
        Self::new(MAX_CONNECTIONS)
    }
}

impl ConnectionLimits {
    /// `per_principal`: most authenticated connections of one principal.
    pub fn new(per_principal: usize) -> Self {
        Self {
            table: Mutex::default(),
            per_principal,
        }
    }

    pub fn per_principal(&self) -> usize {
        self.per_principal
    }

    fn lock(&self) -> MutexGuard<'_, Table> {
        self.table.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Admits `stream` if the limits allow; the returned stream gives its place back when it
    /// closes. `None`: refused (and logged), the stream is dropped (closed) by the caller.
    pub fn admit(self: &Arc<Self>, stream: TcpStream, idle: Duration) -> Option<LimitedStream> {
        let addr = stream.peer_addr().ok()?;
        let ip = addr.ip();
        let mut t = self.lock();
        let (from_ip, pending_ip) = t.per_ip.get(&ip).copied().unwrap_or((0, 0));
        if t.by_addr.len() >= MAX_CONNECTIONS || from_ip >= MAX_PER_ADDRESS {
            let total = t.by_addr.len();
            drop(t);
            warn!(peer = %ip, open = total, from_peer = from_ip, "connection refused: too many open");
            return None;
        }
        // Over a waiting limit, the oldest waiting connection (of this address, or of any) makes
        // room; it stays counted until its stream notices and closes.
        let oldest = if pending_ip >= MAX_PENDING_PER_ADDRESS {
            t.pending
                .iter()
                .find(|&(_, a)| a.ip() == ip)
                .map(|(&serial, _)| serial)
        } else if t.pending.len() >= MAX_PENDING {
            t.pending.keys().next().copied()
        } else {
            None
        };
        if let Some(serial) = oldest
            && let Some(addr) = t.pending.remove(&serial)
        {
            if let Some(e) = t.per_ip.get_mut(&addr.ip()) {
                e.1 -= 1;
            }
            if let Some((conn, _)) = t.by_addr.get(&addr) {
                warn!(peer = %addr, "connection that never authenticated pushed out by a new one");
                conn.evict();
            }
        }
        let serial = t.next_serial;
        t.next_serial += 1;
        let conn = Arc::new(Conn {
            ip,
            serial,
            authenticated: AtomicBool::new(false),
            evicted: AtomicBool::new(false),
            waker: Mutex::new(None),
        });
        let entry = t.per_ip.entry(ip).or_default();
        entry.0 += 1;
        entry.1 += 1;
        t.pending.insert(serial, addr);
        t.by_addr.insert(addr, (conn.clone(), None));
        drop(t);
        Some(LimitedStream {
            stream,
            addr,
            conn,
            limits: self.clone(),
            idle,
            deadline: Box::pin(tokio::time::sleep(idle)),
            handshake: Some(Box::pin(tokio::time::sleep(HANDSHAKE_TIMEOUT))),
        })
    }

    /// A call on the connection from `addr` proved `principal`: the connection stops waiting and
    /// counts against the principal. Refused when the principal holds its limit already.
    pub fn authenticated(
        &self,
        addr: Option<SocketAddr>,
        principal: &Principal,
    ) -> Result<(), Status> {
        let Some(addr) = addr else { return Ok(()) };
        let mut t = self.lock();
        let Some((conn, owner)) = t.by_addr.get(&addr) else {
            return Ok(()); // not a counted connection (served some other way)
        };
        if owner.is_some() {
            return Ok(());
        }
        let conn = conn.clone();
        let held = t.per_principal.get(principal).copied().unwrap_or(0);
        if held >= self.per_principal {
            drop(t);
            warn!(peer = %addr, %principal, held, "connection refused: its credential holds its limit of connections");
            return Err(Status::resource_exhausted(format!(
                "{principal} holds {held} connections, its limit (cluster.max_workers_per_credential × 2)"
            )));
        }
        *t.per_principal.entry(principal.clone()).or_default() += 1;
        t.by_addr.get_mut(&addr).expect("looked up above").1 = Some(principal.clone());
        t.pending.remove(&conn.serial);
        if let Some(e) = t.per_ip.get_mut(&conn.ip) {
            e.1 -= 1;
        }
        conn.authenticated.store(true, Ordering::Release);
        Ok(())
    }

    pub fn open(&self) -> usize {
        self.lock().by_addr.len()
    }

    fn close(&self, addr: SocketAddr) {
        let mut t = self.lock();
        let Some((conn, owner)) = t.by_addr.remove(&addr) else {
            return;
        };
        let was_pending = t.pending.remove(&conn.serial).is_some();
        if let Some(e) = t.per_ip.get_mut(&conn.ip) {
            e.0 -= 1;
            if was_pending {
                e.1 -= 1;
            }
            if e.0 == 0 {
                t.per_ip.remove(&conn.ip);
            }
        }
        if let Some(p) = owner
            && let Some(n) = t.per_principal.get_mut(&p)
        {
            *n -= 1;
            if *n == 0 {
                t.per_principal.remove(&p);
            }
        }
    }
}

/// A TCP stream holding one place in the limits; reading fails with `TimedOut` once the peer has
/// sent nothing for the idle timeout or has not authenticated within the handshake deadline,
/// which makes the server close it.
#[derive(Debug)]
pub struct LimitedStream {
    stream: TcpStream,
    addr: SocketAddr,
    conn: Arc<Conn>,
    limits: Arc<ConnectionLimits>,
    idle: Duration,
    deadline: Pin<Box<Sleep>>,
    /// Until the first authenticated call.
    handshake: Option<Pin<Box<Sleep>>>,
}

impl Drop for LimitedStream {
    fn drop(&mut self) {
        self.limits.close(self.addr);
    }
}

fn timed_out(why: &'static str) -> Poll<io::Result<()>> {
    Poll::Ready(Err(io::Error::new(io::ErrorKind::TimedOut, why)))
}

impl AsyncRead for LimitedStream {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        if self.conn.evicted.load(Ordering::Acquire) {
            return timed_out("pushed out by newer connections before authenticating");
        }
        if self.conn.authenticated.load(Ordering::Acquire) {
            self.handshake = None;
        }
        let before = buf.filled().len();
        match Pin::new(&mut self.stream).poll_read(cx, buf) {
            Poll::Ready(result) => {
                if buf.filled().len() > before {
                    let next = Instant::now() + self.idle;
                    self.deadline.as_mut().reset(next);
                }
                Poll::Ready(result)
            }
            Poll::Pending => {
                *self.conn.waker.lock().unwrap_or_else(|e| e.into_inner()) =
                    Some(cx.waker().clone());
                if let Some(h) = self.handshake.as_mut()
                    && h.as_mut().poll(cx).is_ready()
                {
                    return timed_out("no authenticated call within the handshake deadline");
                }
                match self.deadline.as_mut().poll(cx) {
                    Poll::Ready(()) => timed_out("peer idle for too long"),
                    Poll::Pending => Poll::Pending,
                }
            }
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
mod tests;
