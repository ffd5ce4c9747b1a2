"""The scene file: its schema (pydantic, every key typed), loading with --set overrides, the checks
across keys, and the one-message errors. Layer 0: imports nothing of tidem outside scene/."""
