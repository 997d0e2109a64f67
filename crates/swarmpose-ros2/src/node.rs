//! The node's run: DDS up, the receiving thread, the engine built for the first good
//! pair's camera, then each frame's messages published (and written with `--out`) as
//! soon as the engine returns it; on SIGINT/SIGTERM it stops after the frame in work.

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use swarmpose_odometry::{
    FrameResult, Odometry, OdometryConfig, OdometryError, StereoCamera, StereoInput,
};
use swarmpose_ros::convert::FrameNames;
use swarmpose_ros::msg::{Path, PoseStamped, Time};
use swarmpose_ros::result::{OdometryMessages, key_value, status, tf_of};
use swarmpose_ros::write::FrameMessages;
use swarmpose_runs::output::Summary;

use crate::dds::{Network, Outputs, RosNode, TopicNames};
use crate::error::NodeError;
use crate::frames::{Frame, Frames};
use crate::outputs::RunFiles;
use crate::report::{Reporter, StatusPublisher, count_values, publish_status};
use crate::shared::Shared;

/// Least stream time between two publications of the path, seconds.
pub const PATH_PERIOD_S: f64 = 1.0;

/// What the node is asked to do.
#[derive(Debug, Clone)]
pub struct Settings {
    /// The topics.
    pub topics: TopicNames,
    /// The fixed frame of the poses.
    pub odom_frame: String,
    /// The camera frame (`None`: the images' `frame_id`, else `camera_optical`).
    pub camera_frame: Option<String>,
    /// 1, or 2 (the next frame's front end while the back end works on this one).
    pub threads: u8,
    /// The output folder, if any.
    pub out: Option<PathBuf>,
    /// The engine's settings.
    pub config: OdometryConfig,
}

/// How the node ended.
#[derive(Debug, Clone)]
pub struct Ended {
    /// The frames by status.
    pub summary: Summary,
    /// The intake's counts.
    pub counts: crate::intake::Counts,
    /// The signal that stopped it.
    pub signal: Option<&'static str>,
}

/// The header stamp and completion time of each frame given to the engine, in order.
type Stamps = Arc<Mutex<VecDeque<(i64, Instant)>>>;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// What happens to each result: publication, outputs, counts.
struct Sink {
    outputs: Outputs,
    status: StatusPublisher,
    messages: OdometryMessages,
    path: Path,
    last_path_s: Option<f64>,
    files: Option<RunFiles>,
    shared: Arc<Shared>,
    stamps: Stamps,
    summary: Summary,
    error: Option<NodeError>,
}

impl Sink {
    fn on_frame(&mut self, r: &FrameResult) -> ControlFlow<()> {
        let (stamp_ns, complete) = lock(&self.stamps)
            .pop_front()
            .unwrap_or((0, Instant::now()));
        let odometry = self.messages.odometry(r, stamp_ns);
        let mut extra = count_values(self.shared.intake().counts);
        extra.push(key_value("engine_ms", format!("{:.3}", r.times.total_ms())));
        extra.push(key_value(
            "in_node_ms",
            format!("{:.3}", complete.elapsed().as_secs_f64() * 1e3),
        ));
        let msg = FrameMessages {
            status: status(r, Time::from_nanos(stamp_ns), extra),
            odometry,
            image: None,
            points: None,
            // A live camera has no ground truth.
            ground_truth: None,
        };
        if let Err(e) = self.outputs.odometry.publish(msg.odometry.clone()) {
            eprintln!(
                "swarmpose-ros2: warning: cannot publish frame {}: {e:?}",
                r.index
            );
        }
        if let Err(e) = self.outputs.tf.publish(tf_of(&msg.odometry)) {
            eprintln!(
                "swarmpose-ros2: warning: cannot publish /tf of frame {}: {e:?}",
                r.index
            );
        }
        publish_status(&self.status, msg.status.clone());
        self.path.header = msg.odometry.header.clone();
        self.path.poses.push(PoseStamped {
            header: msg.odometry.header.clone(),
            pose: msg.odometry.pose.pose,
        });
        if self
            .last_path_s
            .is_none_or(|t| r.timestamp_s - t >= PATH_PERIOD_S)
        {
            self.publish_path();
            self.last_path_s = Some(r.timestamp_s);
        }
        self.summary.add(r);
        if let Some(f) = self.files.as_mut()
            && let Err(e) = f.frame(r, &msg)
        {
            self.error = Some(e);
            return ControlFlow::Break(());
        }
        if self.shared.stopped_by().is_some() {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn publish_path(&self) {
        if let Err(e) = self.outputs.path.publish(self.path.clone()) {
            eprintln!("swarmpose-ros2: warning: cannot publish the path: {e:?}");
        }
    }
}

/// Waits for the first pair the engine can be built for; `None` when stopped first.
fn first_engine(frames: &mut Frames, config: &OdometryConfig) -> Option<(Odometry, Frame)> {
    loop {
        let f = frames.next_frame()?;
        let camera = StereoCamera {
            rig: f.rig,
            width: f.frame.left.width,
            height: f.frame.left.height,
        };
        match Odometry::builder(camera).config(config.clone()).build() {
            Ok(o) => return Some((o, f)),
            Err(e) => frames.refuse(format!("the camera of the first pair: {e}")),
        }
    }
}

/// One thread: each frame through the engine in turn; a frame the engine refuses is
/// reported and skipped.
fn run_one_thread(odometry: &mut Odometry, first: Frame, frames: &mut Frames, sink: &mut Sink) {
    let mut next = Some(first);
    while let Some(f) = next {
        let input = StereoInput {
            left: f.frame.left.view(),
            right: f.frame.right.view(),
            timestamp_s: f.frame.timestamp_s,
        };
        lock(&sink.stamps).push_back((f.stamp_ns, f.complete));
        match odometry.track_timed(input, f.frame.load_ms) {
            Ok(r) => {
                if sink.on_frame(&r).is_break() {
                    return;
                }
            }
            Err(e) => {
                lock(&sink.stamps).pop_back();
                frames.refuse(format!("frame at stamp {} ns: {e}", f.stamp_ns));
            }
        }
        next = frames.next_frame();
    }
}

/// Two threads ([`Odometry::run_two_threads`]): the next pair is taken and goes through
/// the front end while the back end works on this one.
fn run_two_threads(
    odometry: &mut Odometry,
    first: Frame,
    frames: &mut Frames,
    sink: &mut Sink,
) -> Result<(), NodeError> {
    let stamps = Arc::clone(&sink.stamps);
    lock(&stamps).push_back((first.stamp_ns, first.complete));
    let rest = std::iter::from_fn(|| {
        let f = frames.next_frame()?;
        lock(&stamps).push_back((f.stamp_ns, f.complete));
        Some(Ok::<_, OdometryError>(f.frame))
    });
    let all = std::iter::once(Ok(first.frame)).chain(rest);
    odometry.run_two_threads(all, &mut |r| sink.on_frame(r))?;
    Ok(())
}

/// Runs the node until SIGINT or SIGTERM.
///
/// # Errors
/// [`NodeError`]: DDS cannot be set up, `--out` cannot be written, or (two threads) the
/// engine fails on a frame.
pub fn run(settings: &Settings, net: Network) -> Result<Ended, NodeError> {
    let shared = Shared::with_signals();
    let mut ros = RosNode::new(net, "swarmpose")?;
    let t = &settings.topics;
    let inputs = ros.inputs(t)?;
    let outputs = ros.outputs(t)?;
    let files = settings.out.as_deref().map(RunFiles::create).transpose()?;
    let status = Arc::new(Mutex::new(ros.status_publisher(t)?));
    let topics = [&t.left, &t.right, &t.left_info, &t.right_info].map(|s| s.clone());
    let receiver = crate::receive::spawn(inputs, Arc::clone(&shared), topics)?;
    let mut frames = Frames::new(
        Arc::clone(&shared),
        t.clone(),
        Reporter::new(Arc::clone(&status)),
    );
    let mut sink = Sink {
        outputs,
        status,
        messages: OdometryMessages::default(),
        path: Path::default(),
        last_path_s: None,
        files,
        shared: Arc::clone(&shared),
        stamps: Stamps::default(),
        summary: Summary::default(),
        error: None,
    };
    let mut result = Ok(());
    if let Some((mut odometry, first)) = first_engine(&mut frames, &settings.config) {
        frames.fix_camera();
        let camera = settings.camera_frame.clone().unwrap_or_else(|| {
            Some(first.frame_id.clone())
                .filter(|f| !f.is_empty())
                .unwrap_or_else(|| FrameNames::default().camera)
        });
        sink.messages = OdometryMessages::new(FrameNames {
            odom: settings.odom_frame.clone(),
            camera,
        });
        if let Some(f) = sink.files.as_mut() {
            f.camera_info(&first.left_info)?;
        }
        eprintln!(
            "swarmpose-ros2: engine started for {}x{} images",
            first.frame.left.width, first.frame.left.height
        );
        result = match settings.threads {
            2 => run_two_threads(&mut odometry, first, &mut frames, &mut sink),
            _ => {
                run_one_thread(&mut odometry, first, &mut frames, &mut sink);
                Ok(())
            }
        };
    }
    shared.stop_receiving();
    let _ = receiver.join();
    if !sink.path.poses.is_empty() {
        sink.publish_path();
    }
    let written = sink.files.take().map_or(Ok(()), RunFiles::finish);
    if let Some(e) = sink.error.take() {
        return Err(e);
    }
    result?;
    written?;
    Ok(Ended {
        summary: sink.summary,
        counts: shared.intake().counts,
        signal: shared.stopped_by(),
    })
}
