"""Jobs: the commands that run scenes (run, limit with its scan, margins, sweep, demo, validate)."""
