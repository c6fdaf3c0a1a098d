"""The base: errors, validated settings, repository paths, atomic file I/O and the pinned ffmpeg.

Nothing here imports another part of lasa, MuJoCo or torch."""
