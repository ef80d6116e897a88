"""The HTML page (html.py) and the figures drawn from the stages' HDF5 files (plots.py, predict_plots.py,
study_plots.py)."""
