//! The listening server, in an async form for tokio callers and a threaded form for sync callers.

use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::sync::oneshot;

use crate::bus::BusRegistry;
use crate::config::HubConfig;
use crate::connection::{ConnectionContext, serve};
use crate::log_limit::LogLimiter;
use crate::stats::{Counters, HubStats, HubStatsHandle};

/// Garbage log lines allowed per second across the whole hub.
const GARBAGE_LOG_BURST: u32 = 10;
/// How long to pause accepting after an accept error such as running out of file descriptors.
const ACCEPT_ERROR_PAUSE: Duration = Duration::from_millis(50);
/// Threads of the runtime [`spawn`] creates; named so their CPU time can be told apart.
pub const HUB_THREAD_NAME: &str = "canopener-hub";

/// A bound, not yet running socketcand-compatible hub.
#[derive(Debug)]
pub struct Hub {
    listener: TcpListener,
    local_addr: SocketAddr,
    context: Arc<ConnectionContext>,
    stats: HubStatsHandle,
}

impl Hub {
    /// Binds the listening socket; call [`Hub::run`] to serve.
    pub async fn bind(config: HubConfig) -> io::Result<Hub> {
        let listener = TcpListener::bind(config.listen).await.map_err(|error| {
            io::Error::new(
                error.kind(),
                format!(
                    "could not listen on {}: {error} (is another hub running? pick another --listen)",
                    config.listen
                ),
            )
        })?;
        let local_addr = listener.local_addr()?;
        let stats = HubStatsHandle::default();
        let counters = Arc::clone(stats.counters());
        let context = ConnectionContext {
            registry: BusRegistry::new(Arc::clone(&counters)),
            counters,
            garbage_log: LogLimiter::new(GARBAGE_LOG_BURST, Duration::from_secs(1)),
            raw_grace: config.raw_grace,
            stall_timeout: config.stall_timeout,
            echo: config.echo,
            max_element_len: config.max_element_len,
            client_queue: config.effective_client_queue(),
        };
        tracing::info!(%local_addr, "socketcand hub listening");
        Ok(Hub {
            listener,
            local_addr,
            context: Arc::new(context),
            stats,
        })
    }

    /// The address the hub listens on, with the real port when the configuration asked for port 0.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// A handle to the counters, valid while and after the hub runs.
    pub fn stats(&self) -> HubStatsHandle {
        self.stats.clone()
    }

    /// Serves clients forever. Accept errors (for example running out of file descriptors) are
    /// logged and retried rather than ending the hub.
    pub async fn run(self) -> io::Result<()> {
        self.run_until(std::future::pending()).await
    }

    /// Serves clients until `shutdown` completes; connections still open then are closed when the
    /// runtime drops their tasks.
    pub async fn run_until(self, shutdown: impl Future<Output = ()>) -> io::Result<()> {
        let next_id = AtomicU64::new(1);
        let mut shutdown = std::pin::pin!(shutdown);
        loop {
            let accepted = tokio::select! {
                accepted = self.listener.accept() => accepted,
                () = &mut shutdown => return Ok(()),
            };
            match accepted {
                Ok((stream, _peer)) => {
                    let id = next_id.fetch_add(1, Ordering::Relaxed);
                    let context = Arc::clone(&self.context);
                    let counters = Arc::clone(&self.context.counters);
                    Counters::add(&counters.clients_connected, 1);
                    Counters::add(&counters.clients_active, 1);
                    tokio::spawn(async move {
                        serve(context, stream, id).await;
                        Counters::sub(&counters.clients_active, 1);
                    });
                }
                Err(error) => {
                    tracing::warn!("accepting a connection failed: {error}; retrying");
                    tokio::time::sleep(ACCEPT_ERROR_PAUSE).await;
                }
            }
        }
    }
}

/// A hub running on its own tokio runtime and thread, for callers without an async runtime.
/// Dropping it shuts the hub down, like [`HubHandle::shutdown`].
#[derive(Debug)]
pub struct HubHandle {
    local_addr: SocketAddr,
    stats: HubStatsHandle,
    stop: Option<oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

/// Starts a hub on a new multi-threaded runtime (one worker per core, threads named
/// [`HUB_THREAD_NAME`]) and returns once it listens.
pub fn spawn(config: HubConfig) -> io::Result<HubHandle> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .thread_name(HUB_THREAD_NAME)
        .build()?;
    let hub = runtime.block_on(Hub::bind(config))?;
    let local_addr = hub.local_addr();
    let stats = hub.stats();
    let (stop, stopped) = oneshot::channel::<()>();
    let thread = std::thread::Builder::new()
        .name(HUB_THREAD_NAME.to_owned())
        .spawn(move || {
            let result = runtime.block_on(hub.run_until(async {
                // A dropped sender also means stop.
                let _ = stopped.await;
            }));
            if let Err(error) = result {
                tracing::error!("hub stopped: {error}");
            }
            runtime.shutdown_timeout(Duration::from_secs(1));
        })?;
    Ok(HubHandle {
        local_addr,
        stats,
        stop: Some(stop),
        thread: Some(thread),
    })
}

impl HubHandle {
    /// The address the hub listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// The hub's counters now.
    pub fn stats(&self) -> HubStats {
        self.stats.snapshot()
    }

    /// A handle to the counters that outlives this handle.
    pub fn stats_handle(&self) -> HubStatsHandle {
        self.stats.clone()
    }

    /// Stops accepting, closes every connection and waits for the hub thread to end.
    pub fn shutdown(mut self) {
        self.stop_and_join();
    }

    fn stop_and_join(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(thread) = self.thread.take()
            && thread.join().is_err()
        {
            tracing::error!("the hub thread panicked");
        }
    }
}

impl Drop for HubHandle {
    fn drop(&mut self) {
        self.stop_and_join();
    }
}
