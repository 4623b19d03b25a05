//! One client connection: the socketcand state machine on the read side, batched writes on the
//! other.
//!
//! States follow socketcand (`doc/protocol.md`, "Modes"): NO_BUS until `< open NAME >`, then BCM
//! (socketcand's default after `open`), RAW after `< rawmode >`, and CONTROL or ISO-TP after their
//! mode commands. Only RAW receives bus traffic; every state that has a bus may `send`.
//! Replies are written alone; unknown or malformed input is logged (rate-limited) and dropped, never
//! answered with `< error … >` once a bus is open, because python-can in raw mode parses every
//! `error` element as an error frame and its receive thread dies on the text.

use std::sync::Arc;
use std::time::Duration;

use canopener_can::CanFrame;
use canopener_socketcand::{ClientCommand, CommandError, ElementReader, parse_client_command};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::sync::{mpsc, watch};

use crate::bus::{Bus, BusRegistry, ClientLink, Outgoing};
use crate::log_limit::LogLimiter;
use crate::stats::Counters;

/// Bytes read from a socket at once; about 300 frames.
const READ_CHUNK: usize = 16 * 1024;
/// Frames published to the bus in one batch at most.
const MAX_PUBLISH_BATCH: usize = 512;
/// Bytes gathered into one socket write at most.
const MAX_WRITE: usize = 64 * 1024;

/// Settings and shared state every connection needs.
#[derive(Debug)]
pub(crate) struct ConnectionContext {
    pub(crate) registry: BusRegistry,
    pub(crate) counters: Arc<Counters>,
    pub(crate) garbage_log: LogLimiter,
    pub(crate) raw_grace: Duration,
    pub(crate) stall_timeout: Duration,
    pub(crate) echo: bool,
    pub(crate) max_element_len: usize,
    pub(crate) client_queue: usize,
}

/// Where the client is in the socketcand protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    NoBus,
    Bcm,
    Raw,
    Control,
    Isotp,
}

/// Serves one client until it disconnects or is dropped.
pub(crate) async fn serve(context: Arc<ConnectionContext>, stream: TcpStream, id: u64) {
    let peer = stream
        .peer_addr()
        .map(|a| a.to_string())
        .unwrap_or_else(|_| "unknown peer".to_owned());
    // Without TCP_NODELAY a lone `< ok >` can wait for the next write and arrive glued to frames.
    if let Err(error) = stream.set_nodelay(true) {
        tracing::warn!(client = id, %peer, "could not set TCP_NODELAY: {error}");
    }
    let (link, outgoing, kill_watch) = ClientLink::new(id, peer.clone(), context.client_queue);
    tracing::info!(client = id, %peer, "client connected");
    let (read_half, write_half) = stream.into_split();
    let mut session = Session {
        context: Arc::clone(&context),
        link: Arc::clone(&link),
        mode: Mode::NoBus,
        bus: None,
    };
    let read_kill_watch = kill_watch.clone();
    let reading = async {
        if session.read_loop(read_half, read_kill_watch).await == ReadEnd::Done {
            // Nothing more will be queued: stop the writer too, unless it is finishing a refusal.
            link.kill();
        }
    };
    let writing = write_loop(&context, &link, write_half, outgoing, kill_watch);
    tokio::join!(reading, writing);
    link.kill();
    if let Some(bus) = session.bus.take() {
        bus.unsubscribe(id).await;
    }
    tracing::info!(client = id, %peer, "client disconnected");
}

/// Why the read side stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ReadEnd {
    /// End of stream, a read error, or the client was killed.
    Done,
    /// A final reply and [`Outgoing::Close`] are queued; the writer closes after sending them.
    Closing,
}

struct Session {
    context: Arc<ConnectionContext>,
    link: Arc<ClientLink>,
    mode: Mode,
    bus: Option<Arc<Bus>>,
}

impl Session {
    async fn read_loop(
        &mut self,
        mut socket: OwnedReadHalf,
        mut kill_watch: watch::Receiver<bool>,
    ) -> ReadEnd {
        if !self.reply(b"< hi >", None).await {
            return ReadEnd::Done;
        }
        let mut reader = ElementReader::new(self.context.max_element_len);
        let mut chunk = vec![0u8; READ_CHUNK];
        // A batch takes one queue slot per frame in every receiver at once, so it must fit a queue.
        let batch_limit = MAX_PUBLISH_BATCH.min(self.context.client_queue);
        let mut frames: Vec<CanFrame> = Vec::with_capacity(batch_limit);
        let mut discarded_before = 0;
        loop {
            let read = tokio::select! {
                read = socket.read(&mut chunk) => read,
                _ = kill_watch.wait_for(|killed| *killed) => break,
            };
            let len = match read {
                Ok(0) => break,
                Ok(len) => len,
                Err(error) => {
                    tracing::debug!(client = self.link.id, "read failed: {error}");
                    break;
                }
            };
            reader.push(chunk.get(..len).unwrap_or_default());
            while let Some(element) = reader.next_element() {
                let element = match element {
                    Ok(element) => element,
                    Err(error) => {
                        self.garbage(format_args!("{error}"));
                        continue;
                    }
                };
                match parse_client_command(&element) {
                    Ok(ClientCommand::Send(frame)) if self.bus.is_some() => {
                        frames.push(frame);
                        if frames.len() >= batch_limit {
                            self.publish(&mut frames).await;
                        }
                    }
                    Ok(command) => {
                        // Frames before a command go out before its effects (e.g. leaving raw mode).
                        self.publish(&mut frames).await;
                        if !self.handle(command).await {
                            return ReadEnd::Done;
                        }
                    }
                    Err(error) => {
                        self.publish(&mut frames).await;
                        if let Some(end) = self.handle_error(error).await {
                            return end;
                        }
                    }
                }
            }
            self.publish(&mut frames).await;
            let discarded = reader.discarded_bytes();
            Counters::add(
                &self.context.counters.discarded_bytes,
                discarded - discarded_before,
            );
            discarded_before = discarded;
            if self.link.is_killed() {
                break;
            }
        }
        ReadEnd::Done
    }

    /// Handles a command; `false` ends the connection.
    async fn handle(&mut self, command: ClientCommand) -> bool {
        match (self.mode, command) {
            (_, ClientCommand::Echo) => self.reply(b"< echo >", None).await,
            (Mode::NoBus, ClientCommand::Open { bus }) => {
                let bus = self.context.registry.open(&bus);
                tracing::info!(client = self.link.id, bus = %bus.name, "bus opened");
                self.bus = Some(bus);
                self.mode = Mode::Bcm;
                self.reply(b"< ok >", None).await
            }
            (Mode::NoBus, command) => {
                self.garbage(format_args!("{command:?} before `< open BUS >`; ignored"));
                true
            }
            (_, ClientCommand::Open { .. }) => {
                self.garbage(format_args!(
                    "a second `< open >` on a connection with a bus; ignored"
                ));
                true
            }
            (_, ClientCommand::RawMode) => {
                let reply = Outgoing::Reply {
                    bytes: b"< ok >",
                    hold: Some(self.context.raw_grace),
                };
                if !self.reserve_reply_slot().await {
                    return false;
                }
                // Queued together with the subscription, so `< ok >` precedes every frame and no
                // frame published after the client could see `< ok >` is missed; the writer then
                // holds frames back for the grace period.
                let queued = match &self.bus {
                    Some(bus) => bus.subscribe(Arc::clone(&self.link), reply).await,
                    None => self.link.outgoing.send(reply).is_ok(),
                };
                self.mode = Mode::Raw;
                queued
            }
            (
                _,
                command @ (ClientCommand::BcmMode | ClientCommand::ControlMode | ClientCommand::IsotpMode),
            ) => {
                if self.mode == Mode::Raw
                    && let Some(bus) = &self.bus
                {
                    bus.unsubscribe(self.link.id).await;
                }
                self.mode = match command {
                    ClientCommand::ControlMode => Mode::Control,
                    ClientCommand::IsotpMode => Mode::Isotp,
                    _ => Mode::Bcm,
                };
                self.reply(b"< ok >", None).await
            }
            (_, ClientCommand::Send(_)) => {
                // Reached only without a bus, which the `NoBus` arm already handles.
                true
            }
            (_, ClientCommand::Other { verb }) => {
                self.garbage(format_args!(
                    "unsupported command `{verb}` in {:?} mode; ignored",
                    self.mode
                ));
                true
            }
        }
    }

    /// Handles an unparsable element; `Some` ends the connection.
    async fn handle_error(&mut self, error: CommandError) -> Option<ReadEnd> {
        if self.mode == Mode::NoBus
            && matches!(
                error,
                CommandError::InvalidBusName { .. }
                    | CommandError::MissingField {
                        field: "bus name",
                        ..
                    }
            )
        {
            tracing::info!(client = self.link.id, "refusing open: {error}");
            // socketcand `state_nobus.c`: refuse and close.
            if self.reply(b"< error could not open bus >", None).await
                && self.link.outgoing.send(Outgoing::Close).is_ok()
            {
                return Some(ReadEnd::Closing);
            }
            return Some(ReadEnd::Done);
        }
        self.garbage(format_args!("{error}"));
        None
    }

    async fn publish(&mut self, frames: &mut Vec<CanFrame>) {
        if frames.is_empty() {
            return;
        }
        if let Some(bus) = &self.bus {
            bus.publish(
                self.link.id,
                frames,
                self.context.echo,
                self.context.stall_timeout,
            )
            .await;
        }
        frames.clear();
    }

    /// Queues a reply; `false` when the client is gone or stalled.
    async fn reply(&self, bytes: &'static [u8], hold: Option<Duration>) -> bool {
        self.reserve_reply_slot().await && self.link.outgoing.send(Outgoing::Reply { bytes, hold }).is_ok()
    }

    /// Takes the queue slot a reply needs; `false` when the client is gone or stalled.
    async fn reserve_reply_slot(&self) -> bool {
        let slot = tokio::time::timeout(self.context.stall_timeout, self.link.queue_slots.acquire()).await;
        match slot {
            Ok(Ok(slot)) => {
                slot.forget();
                true
            }
            Ok(Err(_closed)) => false,
            Err(_elapsed) => {
                if self.link.kill() {
                    tracing::warn!(
                        client = self.link.id,
                        peer = %self.link.peer,
                        "dropping client: it has not read its replies for {:?}",
                        self.context.stall_timeout
                    );
                    Counters::add(&self.context.counters.clients_dropped, 1);
                }
                false
            }
        }
    }

    fn garbage(&self, what: std::fmt::Arguments<'_>) {
        Counters::add(&self.context.counters.garbage_elements, 1);
        if let Some(suppressed) = self.context.garbage_log.allow() {
            tracing::warn!(client = self.link.id, peer = %self.link.peer, suppressed, "dropped input: {what}");
        }
    }
}

/// Writes replies alone and frames in large batches until the client is closed or killed.
async fn write_loop(
    context: &ConnectionContext,
    link: &ClientLink,
    mut socket: OwnedWriteHalf,
    mut outgoing: mpsc::UnboundedReceiver<Outgoing>,
    mut kill_watch: watch::Receiver<bool>,
) {
    let mut hold_until: Option<tokio::time::Instant> = None;
    let mut buffer: Vec<u8> = Vec::with_capacity(MAX_WRITE);
    let mut next: Option<Outgoing> = None;
    loop {
        let item = match next.take() {
            Some(item) => item,
            None => tokio::select! {
                item = outgoing.recv() => match item { Some(item) => item, None => break },
                _ = kill_watch.wait_for(|killed| *killed) => break,
            },
        };
        match item {
            Outgoing::Reply { bytes, hold } => {
                if !write_or_stall(context, link, &mut socket, bytes, &mut kill_watch).await {
                    break;
                }
                link.queue_slots.add_permits(1);
                if let Some(hold) = hold {
                    hold_until = Some(tokio::time::Instant::now() + hold);
                }
            }
            Outgoing::Frames(batch) => {
                if let Some(until) = hold_until.take() {
                    tokio::select! {
                        () = tokio::time::sleep_until(until) => {}
                        _ = kill_watch.wait_for(|killed| *killed) => break,
                    }
                }
                buffer.clear();
                buffer.extend_from_slice(&batch.bytes);
                let mut frames = batch.count as usize;
                // Gather what is already queued into one write: far fewer syscalls under load.
                while buffer.len() < MAX_WRITE {
                    match outgoing.try_recv() {
                        Ok(Outgoing::Frames(more)) => {
                            buffer.extend_from_slice(&more.bytes);
                            frames += more.count as usize;
                        }
                        Ok(other) => {
                            next = Some(other);
                            break;
                        }
                        Err(_) => break,
                    }
                }
                if !write_or_stall(context, link, &mut socket, &buffer, &mut kill_watch).await {
                    break;
                }
                link.queue_slots.add_permits(frames);
                Counters::add(&context.counters.frames_out, frames as u64);
            }
            Outgoing::Close => break,
        }
    }
    link.kill();
    let _ = socket.shutdown().await;
}

/// Writes all of `bytes`; `false` when the client is gone, killed, or made no progress in time.
async fn write_or_stall(
    context: &ConnectionContext,
    link: &ClientLink,
    socket: &mut OwnedWriteHalf,
    bytes: &[u8],
    kill_watch: &mut watch::Receiver<bool>,
) -> bool {
    let write = tokio::time::timeout(context.stall_timeout, socket.write_all(bytes));
    tokio::select! {
        result = write => match result {
            Ok(Ok(())) => true,
            Ok(Err(error)) => {
                tracing::debug!(client = link.id, "write failed: {error}");
                false
            }
            Err(_elapsed) => {
                if link.kill() {
                    tracing::warn!(
                        client = link.id,
                        peer = %link.peer,
                        "dropping client: a write did not finish within {:?} (it stopped reading)",
                        context.stall_timeout
                    );
                    Counters::add(&context.counters.clients_dropped, 1);
                }
                false
            }
        },
        _ = kill_watch.wait_for(|killed| *killed) => false,
    }
}
