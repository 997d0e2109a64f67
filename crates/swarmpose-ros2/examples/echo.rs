//! The transport alone, for the latency benchmark (`bench/latency.py --echo`): takes
//! each `sensor_msgs/Image` on `/probe/image` (sensor data QoS, the node's) and
//! publishes its header back on `/probe/echo` (`std_msgs/Header`, reliable), through
//! the same RustDDS participant setup as the node. `ROS_DOMAIN_ID` and
//! `ROS_LOCALHOST_ONLY` as for the node; `SOCKET_BUFFER_BYTES` sets RustDDS's socket
//! buffers (default 8 MiB). Ends after 10 s without an image.

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use ros2_client::dds::Context;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::rustdds::mio::{Events, Poll, PollOpt, Ready, Token};
use ros2_client::qos::{History, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use swarmpose_ros::msg::{Header, Image};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let domain: u16 = std::env::var("ROS_DOMAIN_ID")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let mut b = DomainParticipantBuilder::new(domain);
    if std::env::var("ROS_LOCALHOST_ONLY").as_deref() == Ok("1") {
        b = b.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    if let Some(n) = std::env::var("SOCKET_BUFFER_BYTES")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        b = b.socket_receive_buffer_size(n).socket_send_buffer_size(n);
    }
    let context = Context::from_domain_participant(b.build()?)?;
    let mut node = context.new_node(NodeName::new("/", "echo")?, NodeOptions::new())?;
    let sensor = QosProfile::subscription_default().history(History::KeepLast { depth: 8 });
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
    let sub = node.create_subscription::<Image>(&images, Some(sensor))?;
    let publisher = node.create_publisher::<Header>(&echo, Some(reliable))?;
    let poll = Poll::new()?;
    poll.register(&sub, Token(0), Ready::readable(), PollOpt::edge())?;
    let mut events = Events::with_capacity(8);
    let mut n = 0u64;
    let mut idle = std::time::Instant::now();
    loop {
        // As the node: a short wait, then drain whatever the event said (RustDDS's
        // edge-triggered readiness alone missed samples here).
        poll.poll(&mut events, Some(Duration::from_millis(20)))?;
        if idle.elapsed() > Duration::from_secs(10) {
            eprintln!("echo: 10 s without an image; {n} images echoed");
            return Ok(());
        }
        while let Some((img, _)) = sub.take()? {
            idle = std::time::Instant::now();
            n += 1;
            if publisher.publish(img.header).is_err() {
                eprintln!("echo: cannot publish");
            }
        }
    }
}
