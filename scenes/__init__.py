"""Scenes shipped with tidem (TOML files); `tidem scenes` lists them."""
