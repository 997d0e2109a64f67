//! The receiving thread: waits on the four subscriptions (mio 0.6 events of RustDDS),
//! takes every sample that arrived, and hands it to the pairing ([`crate::intake`]),
//! waking the engine when a pair is complete. It stops within [`POLL`] of a stop
//! request.

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use ros2_client::dds::Subscription;
use ros2_client::dds::rustdds::mio::{Events, Poll, PollOpt, Ready, Token};
use serde::de::DeserializeOwned;

use crate::dds::Inputs;
use crate::error::NodeError;
use crate::intake::Side;
use crate::shared::Shared;

/// Longest wait for an event before the stop request is checked again.
pub const POLL: Duration = Duration::from_millis(20);

/// Takes every sample waiting in `sub`; a sample that does not decode is counted and
/// named in the intake's `decode_error`.
fn drain<M: DeserializeOwned + 'static>(
    sub: &Subscription<M>,
    shared: &Shared,
    topic: &str,
    mut take: impl FnMut(M),
) {
    loop {
        match sub.take() {
            Ok(Some((m, _))) => take(m),
            Ok(None) => return,
            Err(e) => {
                let mut i = shared.intake();
                i.counts.undecodable += 1;
                i.decode_error = Some(format!("{topic}: a sample does not decode: {e:?}"));
            }
        }
    }
}

/// Starts the receiving thread; `topics` names the left, right, left info and right
/// info topics for messages.
///
/// # Errors
/// [`NodeError::Dds`] when the subscriptions cannot be polled.
pub fn spawn(
    inputs: Inputs,
    shared: Arc<Shared>,
    topics: [String; 4],
) -> Result<JoinHandle<()>, NodeError> {
    let poll = Poll::new().map_err(|e| NodeError::dds("poll", e))?;
    let reg = |e: std::io::Error| NodeError::dds("poll registration", e);
    let edge = PollOpt::edge();
    poll.register(&inputs.left, Token(0), Ready::readable(), edge)
        .map_err(reg)?;
    poll.register(&inputs.right, Token(1), Ready::readable(), edge)
        .map_err(reg)?;
    poll.register(&inputs.left_info, Token(2), Ready::readable(), edge)
        .map_err(reg)?;
    poll.register(&inputs.right_info, Token(3), Ready::readable(), edge)
        .map_err(reg)?;
    Ok(std::thread::spawn(move || {
        let mut events = Events::with_capacity(16);
        while shared.receiving() {
            if poll.poll(&mut events, Some(POLL)).is_err() {
                std::thread::sleep(POLL);
            }
            // Edge-triggered: drain every subscription whatever woke us.
            let s = &*shared;
            drain(&inputs.left_info, s, &topics[2], |m| {
                s.intake().left_info = Some(m)
            });
            drain(&inputs.right_info, s, &topics[3], |m| {
                s.intake().right_info = Some(m);
            });
            let mut paired = false;
            drain(&inputs.left, s, &topics[0], |m| {
                paired |= s.intake().push(Side::Left, m, Instant::now());
            });
            drain(&inputs.right, s, &topics[1], |m| {
                paired |= s.intake().push(Side::Right, m, Instant::now());
            });
            if paired {
                s.notify();
            }
        }
        shared.notify();
    }))
}
