//! `loops replay --serve`: the replay's keyframes, live, over Foxglove's WebSocket protocol, so
//! Foxglove shows the loops appearing as the log plays. The SDK's server speaks the protocol's
//! v1 under its current names, `foxglove.sdk.v1` and `foxglove.sdk.v1.1` (v1 is the former
//! `foxglove.websocket.v1`, renamed); clients that offer only the old name (older Foxglove
//! Studio and Lichtblick releases) are refused at the handshake. The messages are [`loops_io::LiveScene`]'s (the topics and schemas of the scene's MCAP
//! file, built by the same code); this module only serves them.
//!
//! The server is the official `foxglove` crate's [`WebSocketServer`] (its `websocket` feature, a
//! tokio server on a runtime of its own), rather than a WebSocket server of ours: the protocol
//! (advertisements, subscriptions, binary message frames, schema handling) stays Foxglove's to
//! keep right, and the messages' schemas already come from the same crate. The feature is
//! enabled by this crate only, so `loops-io` builds without a network stack; the Python wheel
//! carries it because it carries this command. Channels live in a [`Context`] of the server's
//! own, not the process-wide default one, so nothing else logged in the process reaches the
//! clients.
//!
//! The server sends each message once, to the clients subscribed then: it keeps no history. So
//! the replay waits for a client: it starts once a client has subscribed to every channel, or
//! [`SUBSCRIBE_SETTLE`] after a client's first subscription (Foxglove subscribes only to the
//! topics its panels show). Each client's queue holds every message of the replay (up to
//! [`MAX_BACKLOG`]), so a slow client loses none. At the end of the log the server stays up
//! until its clients leave, at most [`LINGER`] (they receive what is queued), unless `--hold`
//! keeps it up until Ctrl-C; then it stops and its port is closed.

use std::collections::{HashMap, HashSet};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result};
use foxglove::websocket::{ChannelView, Client, ClientId, ServerListener};
use foxglove::{ChannelBuilder, ChannelId, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use loops_core::Interrupt;
use loops_io::{LiveMessage, LiveScene};

/// How long the replay waits, after a client's first subscription, for it to subscribe to the
/// rest before it starts anyway.
pub(crate) const SUBSCRIBE_SETTLE: Duration = Duration::from_secs(1);

/// How long the server stays up after the last keyframe for its clients to receive what is
/// queued, when they do not leave first.
pub(crate) const LINGER: Duration = Duration::from_secs(2);

/// The most messages queued for one client.
pub(crate) const MAX_BACKLOG: usize = 1 << 16;

/// How often the waits look at Ctrl-C.
const POLL: Duration = Duration::from_millis(20);

/// A running server with the live scene's channels (also the Python package's
/// `viewers.serve`).
#[derive(Debug)]
pub struct LiveServer {
    /// The channels' context: the server holds it weakly, so it lives here.
    context: Arc<Context>,
    handle: foxglove::WebSocketServerHandle,
    channels: Vec<Arc<RawChannel>>,
    subscriptions: Arc<Subscriptions>,
    address: SocketAddr,
}

/// What the clients subscribed to so far.
#[derive(Debug, Default)]
struct Subscribed {
    /// The channels of each client.
    channels: HashMap<ClientId, HashSet<ChannelId>>,
    /// When the first subscription came.
    first: Option<Instant>,
}

/// The server's listener: records [`Subscribed`].
#[derive(Debug, Default)]
struct Subscriptions(Mutex<Subscribed>);

impl ServerListener for Subscriptions {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        let mut state = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        state.channels.entry(client.id()).or_default().insert(channel.id());
        state.first.get_or_insert_with(Instant::now);
    }
}

impl LiveServer {
    /// Starts serving the live scene's channels on `address` (port 0: a free port), with room
    /// for `messages` messages in each client's queue.
    ///
    /// # Errors
    /// When the address cannot be bound (taken, or not this machine's).
    pub fn start(address: SocketAddr, messages: usize) -> Result<Self> {
        let context = Context::new();
        let channels = LiveScene::channels()
            .into_iter()
            .map(|c| {
                ChannelBuilder::new(c.topic)
                    .context(&context)
                    .message_encoding(c.message_encoding)
                    .schema(Schema::new(c.schema_name, c.schema_encoding, c.schema_data))
                    .build_raw()
            })
            .collect::<Result<Vec<_>, _>>()?;
        let subscriptions = Arc::new(Subscriptions::default());
        let handle = WebSocketServer::new()
            .name(concat!("loops replay ", env!("CARGO_PKG_VERSION")))
            .context(&context)
            .bind(address.ip().to_string(), address.port())
            .listener(subscriptions.clone())
            .message_backlog_size(messages.clamp(1024, MAX_BACKLOG))
            .start_blocking()
            .with_context(|| format!("--serve {address}: cannot serve there"))?;
        let address = SocketAddr::new(address.ip(), handle.port());
        Ok(Self { context, handle, channels, subscriptions, address })
    }

    /// The address it serves on (with the port picked for port 0).
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Waits until a client has subscribed to every channel, or [`SUBSCRIBE_SETTLE`] after a
    /// client's first subscription; `false` when `stop` came first.
    pub(crate) fn wait_for_client(&self, stop: &Interrupt) -> bool {
        loop {
            if stop.is_interrupted() {
                return false;
            }
            if self.has_client() {
                return true;
            }
            std::thread::sleep(POLL);
        }
    }

    /// Whether a client has subscribed to every channel, or [`SUBSCRIBE_SETTLE`] passed since a
    /// client's first subscription: the replay may start.
    pub fn has_client(&self) -> bool {
        let state = self.subscriptions.0.lock().unwrap_or_else(PoisonError::into_inner);
        let all = state.channels.values().any(|channels| channels.len() >= self.channels.len());
        all || state.first.is_some_and(|first| first.elapsed() >= SUBSCRIBE_SETTLE)
    }

    /// The number of clients connected.
    pub fn client_count(&self) -> usize {
        self.handle.client_count()
    }

    /// Sends `messages` to the clients subscribed to their channels.
    pub fn send(&self, messages: &[LiveMessage]) {
        for message in messages {
            let meta = PartialMetadata { log_time: message.log_time_ns };
            self.channels[message.channel].log_with_meta(&message.data, meta);
        }
    }

    /// Waits until `stop`; with `hold` false, only until every client has left or [`LINGER`]
    /// passed.
    pub(crate) fn hold(&self, hold: bool, stop: &Interrupt) {
        let start = Instant::now();
        while !stop.is_interrupted() && (hold || (self.handle.client_count() > 0 && start.elapsed() < LINGER)) {
            std::thread::sleep(POLL);
        }
    }

    /// Stops the server: the clients are told, its port is closed.
    pub fn close(self) {
        for channel in &self.channels {
            channel.close();
        }
        self.handle.stop().wait_blocking();
        drop(self.context);
    }
}
