use super::*;
use tokio::io::AsyncReadExt;
use tokio::net::TcpListener;

async fn pair(listener: &TcpListener) -> (TcpStream, TcpStream) {
    let client = TcpStream::connect(listener.local_addr().unwrap());
    let (client, server) = tokio::join!(client, listener.accept());
    (client.unwrap(), server.unwrap().0)
}

async fn read_error(stream: &mut LimitedStream) -> io::ErrorKind {
    let mut byte = [0u8; 1];
    stream.read(&mut byte).await.unwrap_err().kind()
}

/// Connections that never authenticate are few at a time per address, the oldest gives way
/// to a new one, and each is closed at the handshake deadline; closing one gives its place
/// back; an authenticated one counts against its principal.
#[tokio::test(start_paused = true)]
async fn connections_that_never_authenticate_cannot_hold_the_slots() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let limits = Arc::new(ConnectionLimits::new(2));
    let mut held = Vec::new();
    for _ in 0..MAX_PENDING_PER_ADDRESS {
        let (client, server) = pair(&listener).await;
        held.push((
            client,
            limits.admit(server, IDLE_TIMEOUT).expect("under the limit"),
        ));
    }
    let (_client, server) = pair(&listener).await;
    let _newest = limits.admit(server, IDLE_TIMEOUT).expect("admitted");
    assert_eq!(
        read_error(&mut held[0].1).await,
        io::ErrorKind::TimedOut,
        "the oldest waiting connection of this address made room"
    );
    held.remove(0);
    assert_eq!(
        limits.open(),
        MAX_PENDING_PER_ADDRESS,
        "a closed one gives its place back"
    );
    held.pop();

    // Authenticated, a connection stops counting as waiting, and survives the deadline.
    let (_c, server) = pair(&listener).await;
    let mut worker = limits.admit(server, IDLE_TIMEOUT).unwrap();
    let alice = Principal::Credential("alice".into());
    limits.authenticated(Some(worker.addr), &alice).unwrap();
    let (_c2, server) = pair(&listener).await;
    let mut waiting = limits.admit(server, IDLE_TIMEOUT).expect("room again");
    assert_eq!(
        read_error(&mut waiting).await,
        io::ErrorKind::TimedOut,
        "handshake deadline"
    );
    drop(waiting);
    tokio::time::advance(HANDSHAKE_TIMEOUT).await;
    let mut byte = [0u8; 1];
    let alive = tokio::time::timeout(Duration::from_millis(10), worker.read(&mut byte)).await;
    assert!(
        alive.is_err(),
        "an authenticated connection is still open (its read waits)"
    );

    // Per principal: two connections, not three.
    let (_c3, server) = pair(&listener).await;
    let second = limits.admit(server, IDLE_TIMEOUT).unwrap();
    limits.authenticated(Some(second.addr), &alice).unwrap();
    let (_c4, server) = pair(&listener).await;
    let third = limits.admit(server, IDLE_TIMEOUT).unwrap();
    let refused = limits.authenticated(Some(third.addr), &alice).unwrap_err();
    assert_eq!(refused.code(), tonic::Code::ResourceExhausted);
    limits
        .authenticated(Some(third.addr), &Principal::Credential("bob".into()))
        .expect("another credential has its own slots");
}

/// With every waiting slot taken, a new connection pushes out the oldest waiting one.
#[tokio::test]
async fn a_new_connection_pushes_out_the_oldest_waiting_one() {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let limits = Arc::new(ConnectionLimits::new(8));
    let oldest = {
        let mut table = limits.lock();
        // Fill the waiting slots as if from many addresses.
        for i in 0..MAX_PENDING as u64 {
            let addr: SocketAddr = format!("10.0.{}.{}:1", i / 200, i % 200 + 1)
                .parse()
                .unwrap();
            let conn = Arc::new(Conn {
                ip: addr.ip(),
                serial: i,
                authenticated: AtomicBool::new(false),
                evicted: AtomicBool::new(false),
                waker: Mutex::new(None),
            });
            table.pending.insert(i, addr);
            table.by_addr.insert(addr, (conn, None));
        }
        table.next_serial = MAX_PENDING as u64;
        table.by_addr[&table.pending[&0]].0.clone()
    };
    let (_client, server) = pair(&listener).await;
    let mut newest = limits.admit(server, IDLE_TIMEOUT).expect("admitted");
    assert!(
        oldest.evicted.load(Ordering::Acquire),
        "the oldest was pushed out"
    );
    limits
        .authenticated(Some(newest.addr), &Principal::Shared)
        .unwrap();
    let mut byte = [0u8; 1];
    let alive = tokio::time::timeout(Duration::from_millis(50), newest.read(&mut byte)).await;
    assert!(alive.is_err(), "the newest is open");
}
