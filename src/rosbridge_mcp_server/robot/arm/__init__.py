"""A robot arm, as the domain sees it (no MCP): its description (``urdf.py``, read through
``bounded_xml.py``), forward kinematics (``kinematics.py``), its controllers and named poses
(``controllers.py``), reading it off the robot (``reading.py``) and what ``diagnose`` says of it
(``health.py``)."""
