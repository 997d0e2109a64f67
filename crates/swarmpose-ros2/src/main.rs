//! `swarmpose-ros2`: a live ROS 2 node without a ROS install (DDS through ros2-client
//! on RustDDS): rectified (or raw, with their camera_info) stereo `sensor_msgs/Image`
//! topics in; `nav_msgs/Odometry` with covariance, `/tf`, `nav_msgs/Path` and the
//! tracking status (`diagnostic_msgs/DiagnosticArray`) out, with the conventions of
//! `odometry.mcap` ([`swarmpose_ros::convert`]). See the README, "ROS 2".
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

mod config;
mod dds;
mod error;
mod frames;
mod intake;
mod node;
mod outputs;
mod receive;
mod report;
mod shared;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

use dds::{Network, TopicNames};
use error::NodeError;
use swarmpose_ros::write::Topics;

/// Stereo visual odometry as a ROS 2 node.
#[derive(Debug, Parser)]
#[command(
    name = "swarmpose-ros2",
    version,
    after_help = "\
The DDS domain is ROS_DOMAIN_ID's (0 when unset); ROS_LOCALHOST_ONLY=1 or \
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST keeps it on the loopback interface. Images and \
camera_info are read with the sensor-data QoS (best effort, keep last); the outputs are \
reliable. Left and right images pair by equal header stamps; when pairs come faster than \
the engine runs, the newest is taken and the others are dropped and counted (the status's \
`dropped`). Problems (no camera_info yet, a camera_info that disagrees with the images, an \
unknown encoding, a side that never sends, a change of size mid-stream) are published as \
the status and printed, and the node goes on. SIGINT or SIGTERM stop it after the frame in \
work (exit status 0); with --out the files written so far are complete."
)]
struct Args {
    /// Left image topic (sensor_msgs/Image).
    #[arg(long, value_name = "TOPIC", default_value = "/stereo/left/image_rect")]
    left: String,
    /// Right image topic.
    #[arg(long, value_name = "TOPIC", default_value = "/stereo/right/image_rect")]
    right: String,
    /// Left camera_info topic (default: camera_info beside the left image topic).
    #[arg(long, value_name = "TOPIC")]
    left_info: Option<String>,
    /// Right camera_info topic (default: camera_info beside the right image topic).
    #[arg(long, value_name = "TOPIC")]
    right_info: Option<String>,
    /// nav_msgs/Odometry topic out.
    #[arg(long, value_name = "TOPIC", default_value = Topics::ODOMETRY)]
    odometry_topic: String,
    /// nav_msgs/Path topic out (the estimate so far, at most once a second).
    #[arg(long, value_name = "TOPIC", default_value = Topics::PATH)]
    path_topic: String,
    /// diagnostic_msgs/DiagnosticArray status topic out.
    #[arg(long, value_name = "TOPIC", default_value = Topics::STATUS)]
    status_topic: String,
    /// tf2_msgs/TFMessage topic out.
    #[arg(long, value_name = "TOPIC", default_value = Topics::TF)]
    tf_topic: String,
    /// The fixed frame of the poses.
    #[arg(long, value_name = "NAME", default_value = "odom")]
    odom_frame: String,
    /// The camera frame (default: the images' frame_id, else camera_optical).
    #[arg(long, value_name = "NAME")]
    camera_frame: Option<String>,
    /// Threads for the engine: 1, or 2 (the next pair's front end while the back end
    /// works on this one).
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u8).range(1..=2))]
    threads: u8,
    /// Also write trajectory.kitti.txt, trajectory.tum.txt, frames.csv,
    /// motion_covariance.csv and odometry.mcap here, frame by frame.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// A recorded run configuration (the config.json of a `swarmpose odometry` run).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

/// `camera_info` beside an image topic: `/a/b/image_rect` -> `/a/b/camera_info`.
fn info_beside(image_topic: &str) -> String {
    match image_topic.rsplit_once('/') {
        Some((dir, _)) => format!("{dir}/camera_info"),
        None => "camera_info".to_owned(),
    }
}

fn run(args: Args) -> Result<(), NodeError> {
    let net = Network::from_env()?;
    let config = config::load_config(args.config.as_deref())?;
    let topics = TopicNames {
        left_info: args.left_info.unwrap_or_else(|| info_beside(&args.left)),
        right_info: args.right_info.unwrap_or_else(|| info_beside(&args.right)),
        left: args.left,
        right: args.right,
        odometry: args.odometry_topic,
        tf: args.tf_topic,
        path: args.path_topic,
        status: args.status_topic,
    };
    eprintln!(
        "swarmpose-ros2: domain {}{}; in: {} + {}, {} + {} (best effort); out: {}, {}, {}, {} \
         (reliable); {} thread(s){}",
        net.domain_id,
        if net.localhost_only {
            " (localhost only)"
        } else {
            ""
        },
        topics.left,
        topics.left_info,
        topics.right,
        topics.right_info,
        topics.odometry,
        topics.tf,
        topics.path,
        topics.status,
        args.threads,
        args.out
            .as_ref()
            .map_or(String::new(), |d| format!("; writing {}", d.display())),
    );
    eprintln!(
        "swarmpose-ros2: engine settings: {}",
        config::settings_line(&config)
    );
    let settings = node::Settings {
        topics,
        odom_frame: args.odom_frame,
        camera_frame: args.camera_frame,
        threads: args.threads,
        out: args.out,
        config,
    };
    let ended = node::run(&settings, net)?;
    let c = ended.counts;
    println!(
        "swarmpose-ros2: {}{}; pairs: {} formed, {} dropped (the engine was behind), {} refused, \
         {} unpaired left, {} unpaired right images",
        ended
            .signal
            .map_or(String::new(), |s| format!("stopped by {s}: ")),
        ended.summary.text(),
        c.pairs,
        c.dropped,
        c.refused,
        c.unpaired_left,
        c.unpaired_right
    );
    Ok(())
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("swarmpose-ros2: error: {e}");
            ExitCode::from(e.exit_status())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_info_is_found_beside_the_image_topic() {
        assert_eq!(
            info_beside("/stereo/left/image_rect"),
            "/stereo/left/camera_info"
        );
        assert_eq!(info_beside("image"), "camera_info");
    }
}
