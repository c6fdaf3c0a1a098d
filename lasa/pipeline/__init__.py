"""The pipeline: notebook execution, a robot's workspace of artifacts, the scale-out of grids (joblib,
Dask), the committed pages, the book, the wall times and ``make verify``."""
