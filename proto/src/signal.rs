//! How either end of the protocol is asked to stop: the coordinator and the worker both end
//! cleanly on the first Ctrl-C or SIGTERM, the signal a terminal, docker, Kubernetes and Slurm send.

/// Resolves at the first Ctrl-C or SIGTERM.
pub async fn termination() {
    let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
    let terminated = async {
        match term.as_mut() {
            Some(t) => {
                t.recv().await;
            }
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        _ = tokio::signal::ctrl_c() => {}
        _ = terminated => {}
    }
}
