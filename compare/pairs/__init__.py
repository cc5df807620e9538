"""Two descriptions of one robot (a URDF and its MJCF, or any two robot files) compared part by part and in
motion: ``urdf2links compare ROBOT.urdf --against ROBOT.xml`` and ``urdf2links report --pairs PAIRS.toml``."""
