"""Frames, movies, plots and the live view of a run (VTK is imported only where frames are drawn).
Layer 5, beside sim/, which it never imports (a Model or Solver comes as an argument): may import
results/ and the layers below it."""
