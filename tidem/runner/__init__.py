"""A run from its start to its last file: the options' checks and launch, the run loop, the run
folder's output and summary, checkpoints, the progress bar, the output size estimate and what
`tidem check` prints. Layer 6: may import sim/, render/ and every layer below."""
