"""Off-screen rendering (OSMesa) and video writing, at a tiny frame size."""

import os

import mediapy
import numpy as np
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.video import (
    label_frames,
    read_video,
    render_states,
    side_by_side,
    write_clips,
    write_video,
)


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


def _clip(seed: int = 0, height: int = 16, width: int = 24) -> np.ndarray:
    """Four frames of a moving colour gradient with a little seeded noise."""
    t, y, x = np.ogrid[:4, :height, :width]
    x, y = 180 * x // width, 180 * y // height
    smooth = np.stack(np.broadcast_arrays(x + 4 * t, y + 16 * t, 200 - (x + y) // 2), axis=-1)
    noise = np.random.default_rng(seed).integers(-8, 9, smooth.shape)
    return np.clip(smooth + noise + 20, 0, 255).astype(np.uint8)


def test_write_video_is_bit_exact(tmp_path):
    clip = _clip()
    a = write_video(tmp_path / "a.mp4", clip).read_bytes()
    b = write_video(tmp_path / "b.mp4", clip.copy()).read_bytes()
    assert a == b
    changed = clip.copy()
    changed[2, 5, 7] = 255 - changed[2, 5, 7]  # one pixel of one frame
    assert write_video(tmp_path / "c.mp4", changed).read_bytes() != a
    back = read_video(tmp_path / "a.mp4")
    assert back.shape == clip.shape and back.dtype == np.uint8
    assert np.abs(back.astype(int) - clip).mean() < 8  # lossy, but the same picture


@pytest.mark.skipif(
    not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2,
    reason="needs CPU affinity and at least two cores (CI and this machine have two)",
)
def test_write_video_ignores_the_core_count(tmp_path):
    # x264 picks threads=1.5 x cores once a frame has enough macroblock rows (64 px here),
    # and the thread count changes the bitstream; the child ffmpeg inherits our affinity.
    clip = _clip(1, height=64, width=96)
    every = os.sched_getaffinity(0)
    a = write_video(tmp_path / "all.mp4", clip).read_bytes()
    try:
        os.sched_setaffinity(0, {min(every)})
        b = write_video(tmp_path / "one.mp4", clip).read_bytes()
    finally:
        os.sched_setaffinity(0, every)
    assert a == b
    assert b"threads=1 " in a


def test_write_video_uses_the_pinned_ffmpeg(tmp_path, monkeypatch):
    fake = tmp_path / "bin" / "ffmpeg"
    fake.parent.mkdir()
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'called'}\nexit 1\n")
    fake.chmod(0o755)
    clip = _clip(2)
    expected = write_video(tmp_path / "a.mp4", clip).read_bytes()
    with monkeypatch.context() as m:
        m.setenv("PATH", f"{fake.parent}{os.pathsep}{os.environ.get('PATH', '')}")
        m.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
        m.setattr(mediapy._config, "ffmpeg_name_or_path", "ffmpeg")  # as in a fresh process
        got = write_video(tmp_path / "b.mp4", clip).read_bytes()
    assert not (tmp_path / "called").exists()
    assert got == expected


@pytest.mark.parametrize("shape", [(2, 15, 24, 3), (2, 16, 24), (16, 24, 3)])
def test_write_video_refuses_bad_shapes(tmp_path, shape):
    with pytest.raises(ConfigError):
        write_video(tmp_path / "v.mp4", np.zeros(shape, np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_read_video_reads_our_videos_with_no_ffmpeg_on_the_path(tmp_path):
    """In a fresh process with no ffmpeg on the PATH, read_video (mediapy with the pinned ffmpeg, set
    where the video is read: `import lasa` installs no hook) reads an MP4 back."""
    import subprocess
    import sys

    clip = _clip(7)
    path = write_video(tmp_path / "v.mp4", clip)
    code = (
        "import sys; from lasa.evidence.video import read_video; v = read_video(sys.argv[1]); "
        "print(v.shape[0], v.shape[1], v.shape[2])"
    )
    env = {**os.environ, "PATH": str(tmp_path / "no-ffmpeg-here")}
    run = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, env=env, check=False
    )
    assert run.returncode == 0, run.stderr[-500:]
    assert run.stdout.split() == [str(len(clip)), str(clip.shape[1]), str(clip.shape[2])]


def test_the_committed_study_video_reads_back_with_its_frame_count():
    """figures/study_dessert.mp4: participant 0's Dessert under the four conditions, every third step
    (notebook 11), so its frame count follows from the episodes' times in figures/study_time.csv."""
    from pathlib import Path

    import pandas as pd

    figures = Path(__file__).resolve().parents[1] / "figures"
    from lasa.evidence.hypotheses import headline_model
    from lasa.experiments.study import run as study

    time = pd.read_csv(figures / "study_time.csv")
    model = headline_model(time, study.Config().participant_models)  # the video's participants
    shown = time[
        (time.participant == 0)
        & (time.task == "Dessert")
        & time.decoder.isin(["transfers", "none"])
        & (time.model == model)
    ]
    shown = shown[shown.assistance.isin(["hindsight", "none"])]
    assert len(shown) == 4
    ends = np.round(shown.total_time.to_numpy() / 0.1).astype(int)
    expected = int(max(end // 3 + 1 for end in ends))  # the longest clip; the others hold their last frame
    video = read_video(figures / "study_dessert.mp4")
    assert video.shape == (expected, 240, 4 * 320, 3)
    with mediapy.VideoReader(str(figures / "study_dessert.mp4")) as reader:  # its header, no second decode
        assert reader.metadata.num_images == expected


def test_write_clips_lays_out_any_number_of_clips(robot, task, tmp_path):
    """Three clips (one per cup of a three-cup scene) side by side and in turn: the frame counts,
    the per-frame captions and the MP4 read back."""
    three = robot.with_cup(robot.goal_positions()[1] + np.array([0.15, 0.0, 0.0]))
    assert len(three.spec.goal_sites) == 3
    aims = [task.goals[0], task.goals[1], task.goals[1] + 0.2]  # a pose towards each cup
    clips = [
        (np.linspace(robot.home, aim, n), [f"cup {g}, t={t}" for t in range(n)] if g else "cup 0")
        for g, (aim, n) in enumerate(zip(aims, (3, 2, 4), strict=True))
    ]
    video, shown = write_clips(three, clips, tmp_path / "side.mp4", fps=5, height=48, width=64)
    assert video.shape == (4, 48, 3 * 64, 3) and [len(c) for c in shown] == [3, 2, 4]
    assert (video[-1, :, 64:128] == shown[1][-1]).all()  # a shorter clip holds its last frame
    assert read_video(tmp_path / "side.mp4").shape == (4, 48, 192, 3)
    plain = render_states(three, clips[2][0], height=48, width=64)
    assert (shown[2] != plain).any() and (shown[2][:, 20:] == plain[:, 20:]).all()  # a caption, at the top
    video, _ = write_clips(three, clips, tmp_path / "turn.mp4", fps=5, layout="in_turn", height=48, width=64)
    assert video.shape == (3 + 2 + 4, 48, 64, 3)
    assert read_video(tmp_path / "turn.mp4").shape[0] == 9


@pytest.mark.parametrize(
    ("clips", "layout", "match"),
    [
        ([], "side_by_side", "at least one clip"),
        ([(np.zeros((0, 5)), "empty")], "side_by_side", "no states"),
        ([(np.zeros((3, 5)), ["one", "two"])], "side_by_side", "2 captions for 3 frames"),
        ([(np.zeros((3, 5)), "x")], "diagonal", "layout"),
    ],
)
def test_write_clips_refuses_bad_input(robot, tmp_path, clips, layout, match):
    with pytest.raises(ConfigError, match=match):
        write_clips(robot, clips, tmp_path / "v.mp4", fps=5, layout=layout, height=16, width=16)
    assert not list(tmp_path.iterdir())  # nothing written


def test_frames_rendered_by_workers_are_the_same_frames(robot, task, tmp_path):
    """render_states over 3 processes gives its frames without workers, in order; write_clips with workers
    writes the same MP4 bytes as without them (a frame is a function of its state alone)."""
    states = np.linspace(robot.home, task.goals[0], 7)
    alone = render_states(robot, states, height=24, width=32)
    assert (render_states(robot, states, height=24, width=32, n_jobs=3) == alone).all()
    clips = [(states[:4], "a"), (states[2:], [f"b{i}" for i in range(5)])]
    write_clips(robot, clips, tmp_path / "one.mp4", fps=5, height=24, width=32)
    write_clips(robot, clips, tmp_path / "two.mp4", fps=5, height=24, width=32, n_jobs=2)
    assert (tmp_path / "one.mp4").read_bytes() == (tmp_path / "two.mp4").read_bytes()


@pytest.mark.parametrize("n_jobs", [0, -1, 1.5])
def test_render_states_refuses_a_bad_worker_count(robot, n_jobs):
    with pytest.raises(ConfigError, match="n_jobs must be a positive integer"):
        render_states(robot, np.zeros((2, robot.n_joints)), height=16, width=16, n_jobs=n_jobs)
