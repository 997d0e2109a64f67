//! The node's status: each processed frame's tracking status (the same as
//! `odometry.mcap`'s, [`swarmpose_ros::result::status`]) with the intake's counts added,
//! and, between frames, the problems that keep frames from the engine. A problem is
//! printed on standard error when it first appears and published at most once a second
//! while it lasts.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use ros2_client::dds::Publisher;
use swarmpose_ros::msg::{DiagnosticArray, KeyValue, Time};
use swarmpose_ros::result::{key_value, status_array};

use crate::intake::Counts;

/// Least time between two publications of the same problem.
pub const REPEAT: Duration = Duration::from_secs(1);

/// The status values of the intake's counts.
#[must_use]
pub fn count_values(c: Counts) -> Vec<KeyValue> {
    vec![
        key_value("pairs", c.pairs),
        key_value("dropped", c.dropped),
        key_value("refused", c.refused),
        key_value("unpaired_left", c.unpaired_left),
        key_value("unpaired_right", c.unpaired_right),
        key_value("out_of_order", c.out_of_order),
        key_value("undecodable", c.undecodable),
    ]
}

/// The status publisher, shared by the engine's threads.
pub type StatusPublisher = Arc<Mutex<Publisher<DiagnosticArray>>>;

/// Publishes `msg` on `publisher`; a failure is printed, not fatal (the odometry goes
/// on).
pub fn publish_status(publisher: &StatusPublisher, msg: DiagnosticArray) {
    let p = publisher
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Err(e) = p.publish(msg) {
        eprintln!("swarmpose-ros2: warning: cannot publish the status: {e:?}");
    }
}

/// Reports problems: printed once, published at most every [`REPEAT`].
pub struct Reporter {
    publisher: StatusPublisher,
    last: Option<(String, Instant)>,
}

impl Reporter {
    /// A reporter publishing on `publisher`.
    #[must_use]
    pub fn new(publisher: StatusPublisher) -> Self {
        Self {
            publisher,
            last: None,
        }
    }

    /// Reports `message` at `level` with the counts.
    pub fn problem(&mut self, level: u8, message: String, counts: Counts) {
        let repeated = self.last.as_ref().is_some_and(|(m, _)| *m == message);
        if repeated
            && self
                .last
                .as_ref()
                .is_some_and(|(_, t)| t.elapsed() < REPEAT)
        {
            return;
        }
        if !repeated {
            eprintln!("swarmpose-ros2: {message}");
        }
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX));
        let msg = status_array(
            Time::from_nanos(now),
            level,
            message.clone(),
            count_values(counts),
        );
        publish_status(&self.publisher, msg);
        self.last = Some((message, Instant::now()));
    }
}
