"""The Warp cloth solver (XPBD / mass-spring) that simulates DARTs on posed bodies. In progress."""
