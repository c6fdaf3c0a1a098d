"""The base (errors, settings, paths, atomic I/O, pinned ffmpeg): no other part of lasa, MuJoCo or torch."""
