"""Jobs: the commands that run scenes (run, limit, margins, demo, validate)."""
