"""The pipeline: the notebook runner, a robot's workspace of artifacts, the scale-out of grids
(joblib, Dask) and the book.
"""
