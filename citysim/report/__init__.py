"""What a planner reads: run and sweep plots, the top-down picture, report.html, camera clips.

The top of the house below cli: may import every stage; nothing but cli imports it."""
