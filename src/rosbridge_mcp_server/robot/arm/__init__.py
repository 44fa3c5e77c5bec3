"""A robot arm, as the domain sees it (no MCP): its description (``urdf.py``), forward kinematics
(``kinematics.py``), and its controllers and named poses (``controllers.py``)."""
