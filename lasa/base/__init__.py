"""The base: errors, validated settings, repository paths, atomic file I/O and the pinned ffmpeg; nothing
here imports another part of lasa, MuJoCo or torch."""
