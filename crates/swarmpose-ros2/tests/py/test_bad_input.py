"""Bad input to swarmpose-ros2, each answered by a status that says what is wrong while
the node goes on (and recovers when the input is good again): images with no
camera_info yet, a right camera that never sends, an unknown encoding, a camera_info
that disagrees with the image size, a change of resolution mid-stream."""

import signal

import numpy as np

from conftest import domain_id
from test_interop import BASE_NS, PERIOD_NS, lockstep


def test_bad_input_is_reported_and_the_node_goes_on(node_factory, peer_factory, kitti):
    domain = domain_id()
    node = node_factory(domain)
    peer = peer_factory(domain)
    peer.wait_matched()
    ns = BASE_NS
    l0, r0 = kitti.left[0], kitti.right[0]

    # A left camera alone: the right one never sends.
    peer.left.write(__import__("dds_peer").image(ns, l0))
    s = peer.wait_status("but no right image on /stereo/right/image_rect", 10)
    assert s.level == 1  # WARN

    # Pairs before any camera_info.
    ns += PERIOD_NS
    peer.pair(ns, l0, r0)
    s = peer.wait_status("no camera_info yet on /stereo/left/camera_info", 10)
    assert s.level == 2  # ERROR

    # An encoding the node does not read (with camera_info now).
    ns += PERIOD_NS
    peer.infos(ns, kitti.p_left, kitti.p_right, kitti.width, kitti.height)
    yuv = np.zeros((kitti.height, kitti.width, 2), np.uint8)
    peer.pair(ns, yuv, yuv, encoding="yuv422")
    peer.wait_status("image encoding 'yuv422' is not one of", 10)

    # camera_info for 1241x376 images, images of half that size.
    ns += PERIOD_NS
    peer.pair(ns, l0[::2, ::2], r0[::2, ::2])
    peer.wait_status(f"camera_info is for {kitti.width}x{kitti.height} images but the images are", 10)
    assert not peer.received

    # Good pairs: the engine starts.
    lockstep(peer, kitti, range(5, 8))

    # A resolution change mid-stream (with a camera_info that agrees with it).
    ns = BASE_NS + 8 * PERIOD_NS
    half_l = [x / 2 for x in kitti.p_left[:8]] + kitti.p_left[8:]
    half_r = [x / 2 for x in kitti.p_right[:8]] + kitti.p_right[8:]
    h, w = kitti.left[8][::2, ::2].shape
    peer.infos(ns, half_l, half_r, w, h)
    peer.pair(ns, kitti.left[8][::2, ::2], kitti.right[8][::2, ::2])
    peer.wait_status(f"the images changed size from {kitti.width}x{kitti.height} to {w}x{h} mid-stream", 10)

    # And back: tracking goes on.
    lockstep(peer, kitti, range(9, 11))
    code, _ = node.stop(signal.SIGINT)
    assert code == 0, node.stderr
    assert len(peer.received) == 5
    refused = [s for a in peer.statuses for s in a.status if s.level == 2]
    assert refused, "errors were published as statuses"
    assert "panicked" not in node.stderr
