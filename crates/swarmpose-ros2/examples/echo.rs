//! The transport alone, for the latency benchmarks (`bench/latency.py`,
//! `bench/transport.py`): takes each `sensor_msgs/Image` on `/probe/image` (sensor data
//! QoS, the node's) and publishes its header back on `/probe/echo` (`std_msgs/Header`,
//! reliable), through the same RustDDS participant setup as the node. `ROS_DOMAIN_ID`
//! and `ROS_LOCALHOST_ONLY` as for the node. Ends after 10 s without an image.
//!
//! For the comparisons of the benchmarks:
//! - `SOCKET_BUFFER_BYTES` sets RustDDS's socket buffers (default 8 MiB);
//! - `ECHO_EVENTS=mio06` waits with RustDDS's mio 0.6 readiness, as the node did before,
//!   instead of its mio 1 readiness (the node's): RustDDS 0.15.1 never re-arms the mio
//!   0.6 one, so each wait ends on its 20 ms timeout;
//! - `ECHO_IMAGE_QOS=reliable` subscribes to the images reliably (the publisher must be
//!   reliable too) instead of best effort.

use std::net::{IpAddr, Ipv4Addr};
use std::time::{Duration, Instant};

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::rustdds::{mio, mio1};
use ros2_client::dds::{Context, Publisher, Subscription};
use ros2_client::qos::{History, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use swarmpose_ros::msg::{Header, Image};

/// Longest wait for an event (the node's `receive::POLL`).
const POLL: Duration = Duration::from_millis(20);

/// Waits at most [`POLL`] for a sample, with one of RustDDS's two readiness APIs.
enum Waiter {
    Mio1(mio1::Poll, mio1::Events),
    Mio06(mio::Poll, mio::Events),
}

impl Waiter {
    fn new(sub: &mut Subscription<Image>, mio06: bool) -> std::io::Result<Self> {
        if mio06 {
            let poll = mio::Poll::new()?;
            let (ready, edge) = (mio::Ready::readable(), mio::PollOpt::edge());
            poll.register(&*sub, mio::Token(0), ready, edge)?;
            Ok(Self::Mio06(poll, mio::Events::with_capacity(8)))
        } else {
            let poll = mio1::Poll::new()?;
            let read = mio1::Interest::READABLE;
            poll.registry().register(sub, mio1::Token(0), read)?;
            Ok(Self::Mio1(poll, mio1::Events::with_capacity(8)))
        }
    }

    fn wait(&mut self) -> std::io::Result<()> {
        match self {
            Self::Mio1(p, e) => p.poll(e, Some(POLL)),
            Self::Mio06(p, e) => p.poll(e, Some(POLL)).map(|_| ()),
        }
    }
}

fn env(key: &str) -> Option<String> {
    std::env::var(key).ok()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let domain: u16 = env("ROS_DOMAIN_ID")
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let mut b = DomainParticipantBuilder::new(domain);
    if env("ROS_LOCALHOST_ONLY").as_deref() == Some("1") {
        b = b.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    if let Some(n) = env("SOCKET_BUFFER_BYTES").and_then(|s| s.parse().ok()) {
        b = b.socket_receive_buffer_size(n).socket_send_buffer_size(n);
    }
    let context = Context::from_domain_participant(b.build()?)?;
    let mut node = context.new_node(NodeName::new("/", "echo")?, NodeOptions::new())?;
    let mut sensor = QosProfile::subscription_default().history(History::KeepLast { depth: 8 });
    if env("ECHO_IMAGE_QOS").as_deref() == Some("reliable") {
        sensor = sensor.reliability_reliable(WhenFull::DEFAULT);
    }
    let reliable = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .history(History::KeepLast { depth: 100 });
    let images = node.create_topic(
        &Name::new("/probe", "image")?,
        MessageTypeName::new("sensor_msgs", "Image"),
        &sensor,
    )?;
    let echo = node.create_topic(
        &Name::new("/probe", "echo")?,
        MessageTypeName::new("std_msgs", "Header"),
        &reliable,
    )?;
    let mut sub = node.create_subscription::<Image>(&images, Some(sensor))?;
    let publisher = node.create_publisher::<Header>(&echo, Some(reliable))?;
    let mut waiter = Waiter::new(&mut sub, env("ECHO_EVENTS").as_deref() == Some("mio06"))?;
    serve(&mut waiter, &sub, &publisher)
}

/// Echoes until 10 s pass without an image.
fn serve(
    waiter: &mut Waiter,
    sub: &Subscription<Image>,
    publisher: &Publisher<Header>,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut n = 0u64;
    let mut idle = Instant::now();
    loop {
        // As the node: wait, then take whatever arrived.
        waiter.wait()?;
        if idle.elapsed() > Duration::from_secs(10) {
            eprintln!("echo: 10 s without an image; {n} images echoed");
            return Ok(());
        }
        while let Some((img, _)) = sub.take()? {
            idle = Instant::now();
            n += 1;
            if publisher.publish(img.header).is_err() {
                eprintln!("echo: cannot publish");
            }
        }
    }
}
