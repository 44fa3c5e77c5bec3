"""What the watch tools show a model, drawn or shortened from what robot/ reads: maps, scans, charts, camera
frames as pictures (Pillow is imported here and in the simulated robot only), and long messages summarised.

Above ``robot/`` (it reads robot/'s data: a grid, a series, the decode budget), below ``tools/`` and
``console/``, which import it; ``robot/`` never imports it. No MCP, no I/O.
"""
