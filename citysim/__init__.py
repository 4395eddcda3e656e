"""citysim: a street-lighting scenario simulator that proves the paper's detector.

Imports ``detector``; ``detector`` never imports ``citysim``.
"""

__version__ = "0.1.0"
