"""swarmpose.Sequence and swarmpose.odometry on ROS 2 bags (written at test time by the
independent `rosbags` writer from the first KITTI frames): the same frames and the same
trajectory, bit for bit, as the folder they were made from, for an MCAP file (plain and
zstd), a .db3 file and a rosbag2 folder; a bad bag raises with the command line's
message."""

import subprocess

import numpy as np
import pytest

import swarmpose
from bags import file_in, frames_dir, kitti_clip, make_bag, require_rosbags

FRAMES = 6


@pytest.fixture
def kitti_bags(kitti_seq2, tmp_path):
    """The KITTI clip folder and its bags: {name: path}."""
    require_rosbags()
    folder = kitti_clip(kitti_seq2, tmp_path / "kitti", FRAMES)
    frames = frames_dir(swarmpose.Sequence(folder), folder / "calib.txt", tmp_path / "frames")
    bags = {"folder": folder}
    for storage in ("mcap", "mcap-zstd", "sqlite3"):
        bag = make_bag(frames, tmp_path / storage, storage)
        bags[storage + " folder"] = bag
        bags[storage + " file"] = file_in(bag, ".db3" if storage == "sqlite3" else ".mcap")
    return bags


def test_a_bag_gives_the_folder_trajectory(kitti_bags):
    folder = swarmpose.Sequence(kitti_bags["folder"])
    want = swarmpose.odometry(kitti_bags["folder"])
    assert len(want) == FRAMES
    for name, path in kitti_bags.items():
        if name == "folder":
            continue
        seq = swarmpose.Sequence(path)
        assert (seq.layout, len(seq)) == ("ros2 bag", FRAMES), name
        assert seq.topics == ("/stereo/left/image_rect", "/stereo/right/image_rect")
        assert seq.unpaired == []
        assert seq.camera == folder.camera, name
        assert np.diff(seq.stamps_ns).tolist() == [100_000_000] * (FRAMES - 1)
        for k in (0, FRAMES - 1):
            for a, b in zip(seq[k], folder[k]):
                assert np.array_equal(a, b), (name, k)
        run = swarmpose.odometry(path)
        assert np.array_equal(run.poses, want.poses), name
        assert run.statuses == want.statuses, name
        assert np.allclose(run.timestamps, want.timestamps, atol=1e-9, rtol=0), name
    # Topics named as found give the same run.
    named = swarmpose.odometry(kitti_bags["mcap file"], left="/stereo/left/image_rect",
                               right="/stereo/right/image_rect", stamp_tolerance=1.0)
    assert np.array_equal(named.poses, want.poses)


def test_a_bad_bag_raises_the_command_line_message(kitti_bags, swarmpose_bin, tmp_path):
    bag = kitti_bags["mcap file"]
    with pytest.raises(ValueError) as e:
        swarmpose.Sequence(bag, left="/nope", right="/stereo/right/image_rect")
    message = str(e.value)
    assert "no topic /nope" in message and "sensor_msgs/msg/Image" in message, message
    cli = subprocess.run([str(swarmpose_bin), "odometry", str(bag), "--left", "/nope", "--right",
                          "/stereo/right/image_rect", "--out", str(tmp_path / "out"), "--quiet"],
                         capture_output=True, text=True)
    assert cli.returncode == 2
    assert message in cli.stderr, (message, cli.stderr)
    with pytest.raises(ValueError, match="name both the left and the right topic"):
        swarmpose.odometry(bag, left="/stereo/left/image_rect")
    with pytest.raises(ValueError, match="stamp_tolerance: the stamp tolerance must be"):
        swarmpose.Sequence(bag, stamp_tolerance=-1.0)
    with pytest.raises(ValueError, match="topics are named for a ROS 2 bag"):
        swarmpose.Sequence(kitti_bags["folder"], left="/a", right="/b")
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    with pytest.raises(ValueError, match="empty.mcap"):
        swarmpose.odometry(empty)
