"""Frames, movies, plots and the live view of a run (VTK is imported only where frames are drawn)."""
