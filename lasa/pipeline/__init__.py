"""The pipeline: notebook runs, a robot's workspace, the grids' scale-out, pages, book, wall times, verify."""
