//! The receiving thread: waits on the four subscriptions (mio 1 events of RustDDS),
//! takes every sample that arrived, and hands it to the pairing ([`crate::intake`]),
//! waking the engine when a pair is complete. It stops within [`POLL`] of a stop
//! request.
//!
//! Not mio 0.6: RustDDS 0.15.1 sets a reader's mio 0.6 readiness on the first sample and
//! never clears it (`take` drains its other notification channels, not that one), so an
//! edge-triggered mio 0.6 wait woke only on its timeout and every image waited up to
//! [`POLL`] (the 12 ms p50 and 22 ms p99 of the echo benchmark before; bench/README.md).
//! Its mio 1 readiness is a socket pair that `take` drains, so each sample wakes us.

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use ros2_client::dds::Subscription;
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};
use serde::de::DeserializeOwned;

use crate::dds::Inputs;
use crate::error::NodeError;
use crate::intake::Side;
use crate::shared::Shared;

/// Longest wait for an event before the stop request is checked again (samples wake the
/// thread at once: this bounds only the time to stop).
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

/// A poll that wakes on a sample of any of `inputs` (tokens 0 to 3: left, right, left
/// info, right info).
fn register(inputs: &mut Inputs) -> Result<Poll, NodeError> {
    let poll = Poll::new().map_err(|e| NodeError::dds("poll", e))?;
    let reg = |e: std::io::Error| NodeError::dds("poll registration", e);
    let r = poll.registry();
    let read = Interest::READABLE;
    r.register(&mut inputs.left, Token(0), read).map_err(reg)?;
    r.register(&mut inputs.right, Token(1), read).map_err(reg)?;
    r.register(&mut inputs.left_info, Token(2), read)
        .map_err(reg)?;
    r.register(&mut inputs.right_info, Token(3), read)
        .map_err(reg)?;
    Ok(poll)
}

/// Starts the receiving thread; `topics` names the left, right, left info and right
/// info topics for messages.
///
/// # Errors
/// [`NodeError::Dds`] when the subscriptions cannot be polled.
pub fn spawn(
    mut inputs: Inputs,
    shared: Arc<Shared>,
    topics: [String; 4],
) -> Result<JoinHandle<()>, NodeError> {
    let mut poll = register(&mut inputs)?;
    Ok(std::thread::spawn(move || {
        let mut events = Events::with_capacity(16);
        while shared.receiving() {
            if poll.poll(&mut events, Some(POLL)).is_err() {
                std::thread::sleep(POLL);
            }
            // Edge-triggered (each `take` drains the readiness): take everything from
            // every subscription whatever woke us.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dds::{IMAGE_DEPTH, Network, RosNode, TopicNames, sensor_qos};
    use swarmpose_ros::msg::{Header, Image, Time};

    fn image(ns: i64) -> Image {
        Image {
            header: Header {
                stamp: Time::from_nanos(ns),
                frame_id: "camera".into(),
            },
            height: 4,
            width: 64,
            encoding: "mono8".into(),
            is_bigendian: 0,
            step: 64,
            data: vec![7; 256],
        }
    }

    fn names() -> TopicNames {
        let t = |s: &str| format!("/wake_test/{s}");
        TopicNames {
            left: t("left"),
            right: t("right"),
            left_info: t("left_info"),
            right_info: t("right_info"),
            odometry: t("odometry"),
            tf: t("tf"),
            path: t("path"),
            status: t("status"),
        }
    }

    /// The stamps of the left images taken from `inputs` now.
    fn take_left(inputs: &Inputs) -> Vec<i64> {
        let mut got = Vec::new();
        while let Ok(Some((m, _))) = inputs.left.take() {
            got.push(m.header.stamp.as_nanos());
        }
        got
    }

    /// Every sample wakes the receiving thread's wait, not only the first: the node's
    /// latency rests on it. (RustDDS 0.15.1's mio 0.6 readiness, which the node used
    /// before, is set by the first sample and never re-armed: there the wait for the
    /// second sample ends on its timeout with no event, and this test fails.)
    #[test]
    fn every_sample_wakes_the_wait() -> Result<(), Box<dyn std::error::Error>> {
        let net = Network {
            domain_id: 211,
            localhost_only: true,
        };
        let mut receiver = RosNode::new(net, "wake_test_receiver")?;
        let mut inputs = receiver.inputs(&names())?;
        let mut poll = register(&mut inputs)?;
        let mut sender = RosNode::new(net, "wake_test_sender")?;
        let left = sender.publisher::<Image>(&names().left, sensor_qos(IMAGE_DEPTH))?;
        let mut events = Events::with_capacity(16);
        // Discovery: publish until the first image arrives (best effort drops the
        // samples sent before the endpoints match).
        let start = Instant::now();
        while take_left(&inputs).is_empty() {
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "no discovery within 30 s"
            );
            left.publish(image(0))?;
            poll.poll(&mut events, Some(Duration::from_millis(100)))?;
        }
        for k in 1..=5 {
            left.publish(image(k))?;
            poll.poll(&mut events, Some(Duration::from_secs(10)))?;
            let woke = events.iter().any(|e| e.token() == Token(0));
            assert!(
                woke,
                "image {k}: the wait ended on its 10 s timeout, without an event"
            );
            let mut got = take_left(&inputs);
            let end = Instant::now() + Duration::from_secs(10);
            while !got.contains(&k) && Instant::now() < end {
                poll.poll(&mut events, Some(Duration::from_millis(100)))?;
                got.extend(take_left(&inputs));
            }
            assert!(
                got.contains(&k),
                "image {k} woke the wait but was not taken: {got:?}"
            );
        }
        Ok(())
    }
}
