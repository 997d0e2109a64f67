//! The node's DDS side (ros2-client on RustDDS): the participant (domain from
//! `ROS_DOMAIN_ID`, loopback only when `ROS_LOCALHOST_ONLY=1` or
//! `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`), the subscriptions and publishers, and
//! their QoS: sensor data (best effort, keep last) for the images and camera_info, as
//! camera drivers publish them; reliable for what the node publishes.

use std::net::{IpAddr, Ipv4Addr};

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::{Context, Node, Publisher, Subscription};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use serde::Serialize;
use serde::de::DeserializeOwned;
use swarmpose_ros::msg::{
    CameraInfo, DiagnosticArray, Image, Odometry, Path, RosMessage, TfMessage,
};

use crate::error::NodeError;

/// Depth of the image subscriptions' history: enough for the images that arrive while
/// the receiving thread is busy, so that the node, not DDS, decides what to drop (and
/// counts it).
pub const IMAGE_DEPTH: usize = 8;

/// The topic names, in and out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicNames {
    /// Left `sensor_msgs/Image`.
    pub left: String,
    /// Right `sensor_msgs/Image`.
    pub right: String,
    /// Left `sensor_msgs/CameraInfo`.
    pub left_info: String,
    /// Right `sensor_msgs/CameraInfo`.
    pub right_info: String,
    /// `nav_msgs/Odometry` out.
    pub odometry: String,
    /// `tf2_msgs/TFMessage` out.
    pub tf: String,
    /// `nav_msgs/Path` out.
    pub path: String,
    /// `diagnostic_msgs/DiagnosticArray` out.
    pub status: String,
}

/// The DDS domain and network of the node, from the ROS 2 environment variables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Network {
    /// `ROS_DOMAIN_ID` (0 when unset).
    pub domain_id: u16,
    /// Loopback only.
    pub localhost_only: bool,
}

impl Network {
    /// From `ROS_DOMAIN_ID`, `ROS_LOCALHOST_ONLY` and `ROS_AUTOMATIC_DISCOVERY_RANGE`.
    ///
    /// # Errors
    /// [`NodeError::Usage`] for a `ROS_DOMAIN_ID` that is not 0..=232.
    pub fn from_env() -> Result<Self, NodeError> {
        let var = |k: &str| std::env::var(k).ok().map(|v| v.trim().to_owned());
        let domain_id = match var("ROS_DOMAIN_ID").filter(|v| !v.is_empty()) {
            None => 0,
            Some(v) => v.parse::<u16>().ok().filter(|d| *d <= 232).ok_or_else(|| {
                NodeError::Usage(format!(
                    "ROS_DOMAIN_ID={v}: a DDS domain is a whole number from 0 to 232"
                ))
            })?,
        };
        let localhost_only = var("ROS_LOCALHOST_ONLY").as_deref() == Some("1")
            || var("ROS_AUTOMATIC_DISCOVERY_RANGE")
                .is_some_and(|v| v.eq_ignore_ascii_case("LOCALHOST"));
        Ok(Self {
            domain_id,
            localhost_only,
        })
    }
}

/// Sensor data QoS (best effort, volatile, keep last `depth`).
pub(crate) fn sensor_qos(depth: usize) -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast { depth })
}

/// Reliable QoS, keep last `depth`.
fn reliable_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// The ROS 2 name of a topic (`/a/b`, `a/b`).
fn topic_name(topic: &str) -> Result<Name, NodeError> {
    Name::parse(topic)
        .map_err(|e| NodeError::Usage(format!("topic '{topic}' is not a ROS 2 name: {e}")))
}

/// `pkg/msg/Name` as ros2-client's type name.
fn type_name<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let pkg = parts.next().unwrap_or_default();
    let name = parts.next_back().unwrap_or_default();
    MessageTypeName::new(pkg, name)
}

/// The node's subscriptions.
pub struct Inputs {
    /// Left images.
    pub left: Subscription<Image>,
    /// Right images.
    pub right: Subscription<Image>,
    /// Left camera_info.
    pub left_info: Subscription<CameraInfo>,
    /// Right camera_info.
    pub right_info: Subscription<CameraInfo>,
}

/// The node's publishers.
pub struct Outputs {
    /// `nav_msgs/Odometry`.
    pub odometry: Publisher<Odometry>,
    /// `/tf`.
    pub tf: Publisher<TfMessage>,
    /// `nav_msgs/Path`.
    pub path: Publisher<Path>,
}

/// The ROS 2 node and its topics. Dropping it leaves the DDS domain.
pub struct RosNode {
    node: Node,
    _context: Context,
}

impl RosNode {
    /// Joins the domain of `net` as node `name`.
    ///
    /// # Errors
    /// [`NodeError::Dds`] when the participant or node cannot be created.
    pub fn new(net: Network, name: &str) -> Result<Self, NodeError> {
        let mut b = DomainParticipantBuilder::new(net.domain_id);
        if net.localhost_only {
            b = b.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
        }
        let participant = b.build().map_err(|e| NodeError::dds("participant", e))?;
        let context = Context::from_domain_participant(participant)
            .map_err(|e| NodeError::dds("context", e))?;
        let node = context
            .new_node(
                NodeName::new("/", name).map_err(|e| NodeError::Usage(e.to_string()))?,
                NodeOptions::new(),
            )
            .map_err(|e| NodeError::dds("node", e))?;
        Ok(Self {
            node,
            _context: context,
        })
    }

    fn subscribe<M: RosMessage + DeserializeOwned + 'static>(
        &mut self,
        topic: &str,
        qos: QosProfile,
    ) -> Result<Subscription<M>, NodeError> {
        let t = self
            .node
            .create_topic(&topic_name(topic)?, type_name::<M>(), &qos)
            .map_err(|e| NodeError::dds(topic, e))?;
        self.node
            .create_subscription::<M>(&t, Some(qos))
            .map_err(|e| NodeError::dds(topic, e))
    }

    /// A publisher of `topic` with `qos`.
    pub(crate) fn publisher<M: RosMessage + Serialize>(
        &mut self,
        topic: &str,
        qos: QosProfile,
    ) -> Result<Publisher<M>, NodeError> {
        let t = self
            .node
            .create_topic(&topic_name(topic)?, type_name::<M>(), &qos)
            .map_err(|e| NodeError::dds(topic, e))?;
        self.node
            .create_publisher::<M>(&t, Some(qos))
            .map_err(|e| NodeError::dds(topic, e))
    }

    /// Subscribes to the images and camera_info of `names`.
    ///
    /// # Errors
    /// [`NodeError::Usage`] for a bad topic name, [`NodeError::Dds`].
    pub fn inputs(&mut self, names: &TopicNames) -> Result<Inputs, NodeError> {
        Ok(Inputs {
            left: self.subscribe(&names.left, sensor_qos(IMAGE_DEPTH))?,
            right: self.subscribe(&names.right, sensor_qos(IMAGE_DEPTH))?,
            left_info: self.subscribe(&names.left_info, sensor_qos(1))?,
            right_info: self.subscribe(&names.right_info, sensor_qos(1))?,
        })
    }

    /// Creates the publishers of `names` but the status's.
    ///
    /// # Errors
    /// [`NodeError::Usage`] for a bad topic name, [`NodeError::Dds`].
    pub fn outputs(&mut self, names: &TopicNames) -> Result<Outputs, NodeError> {
        Ok(Outputs {
            odometry: self.publisher(&names.odometry, reliable_qos(10))?,
            tf: self.publisher(&names.tf, reliable_qos(100))?,
            path: self.publisher(&names.path, reliable_qos(1))?,
        })
    }

    /// Creates the status publisher of `names`.
    ///
    /// # Errors
    /// [`NodeError::Usage`] for a bad topic name, [`NodeError::Dds`].
    pub fn status_publisher(
        &mut self,
        names: &TopicNames,
    ) -> Result<Publisher<DiagnosticArray>, NodeError> {
        self.publisher(&names.status, reliable_qos(10))
    }
}
