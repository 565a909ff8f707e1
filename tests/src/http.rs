//! A dashboard seen over plain HTTP, as a browser or `curl` sees it: one GET on a fresh
//! connection, and a store's dashboard served on a runtime of its own.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::Duration;

use amorph_coordinator::dashboard::{self, DashboardError};

/// One HTTP/1.1 GET: (status code, headers in lower case, body).
pub fn get(
    addr: SocketAddr,
    path: &str,
    headers: &[(&str, &str)],
) -> (u16, HashMap<String, String>, Vec<u8>) {
    let mut stream = TcpStream::connect(addr).expect("the dashboard accepts connections");
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n");
    for (k, v) in headers {
        request.push_str(&format!("{k}: {v}\r\n"));
    }
    request.push_str("\r\n");
    stream.write_all(request.as_bytes()).unwrap();
    let mut reply = Vec::new();
    stream.read_to_end(&mut reply).unwrap();
    let split = reply
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a header");
    let head = String::from_utf8(reply[..split].to_vec()).unwrap();
    let mut lines = head.lines();
    let code = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let headers: HashMap<String, String> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_owned()))
        .collect();
    let mut body = reply[split + 4..].to_vec();
    if headers
        .get("transfer-encoding")
        .is_some_and(|t| t == "chunked")
    {
        body = unchunk(&body);
    }
    (code, headers, body)
}

fn unchunk(mut data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let end = data.windows(2).position(|w| w == b"\r\n").unwrap();
        let size =
            usize::from_str_radix(std::str::from_utf8(&data[..end]).unwrap().trim(), 16).unwrap();
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&data[end + 2..end + 2 + size]);
        data = &data[end + 4 + size..];
    }
}

/// Serves `store` on `listen` from a runtime of its own; the runtime must outlive the requests.
pub fn serve_store(
    store: &Path,
    listen: &str,
    token: Option<&str>,
) -> (
    tokio::runtime::Runtime,
    Result<dashboard::Dashboard, DashboardError>,
) {
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let served = runtime.block_on(async {
        dashboard::bind(listen, token.map(str::to_owned))
            .await?
            .serve(store, None)
            .await
    });
    (runtime, served)
}

/// `/api/status` of the store's dashboard, served on loopback for the one request.
pub fn store_status(store: &Path) -> serde_json::Value {
    let (runtime, served) = serve_store(store, "127.0.0.1:0", None);
    let served = served.expect("the store's dashboard is served");
    let (code, _, body) = get(served.addr, "/api/status", &[]);
    assert_eq!(code, 200, "{}", String::from_utf8_lossy(&body));
    runtime.block_on(served.shutdown());
    serde_json::from_slice(&body).expect("the status is JSON")
}
