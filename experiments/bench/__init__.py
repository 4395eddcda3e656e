"""Speed and memory figures (make bench): detector against OpenCV's floor, renderer, simulation, sweeps."""
