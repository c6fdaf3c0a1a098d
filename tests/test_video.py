"""Off-screen rendering (OSMesa) and video writing, at a tiny frame size."""

import numpy as np
import pytest

from lasa.errors import ConfigError
from lasa.video import label_frames, read_video, render_states, side_by_side, write_video


def test_render_shows_the_arm_move(robot, task):
    frames = render_states(robot, np.stack([robot.home, task.goals[1]]), height=48, width=64)
    assert frames.shape == (2, 48, 64, 3) and frames.dtype == np.uint8
    assert frames.std() > 5  # not a blank image
    assert np.abs(frames[0].astype(int) - frames[1]).mean() > 1  # the pose changed the picture


def test_odd_frame_size_is_refused(robot):
    with pytest.raises(ConfigError, match="even"):
        render_states(robot, robot.home[None], height=47, width=64)


def test_write_video_round_trip(tmp_path):
    frames = np.zeros((6, 32, 48, 3), np.uint8)
    frames[:, :, :24] = 255
    clip = side_by_side(label_frames(frames, "LA"), frames[:4])
    assert clip.shape == (6, 32, 96, 3)
    path = write_video(tmp_path / "v.mp4", clip, fps=5)
    back = read_video(path)
    assert back.shape[0] == 6 and back.shape[1:3] == (32, 96)
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]
