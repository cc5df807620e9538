"""The MuJoCo side: the same model in MuJoCo (route 1, the project's tree as MJCF; route 2, MuJoCo's URDF
import), its runs and the scene's inputs as a compiled control callback.

May import anything under ``urdf2links`` but ``cli``, and ``urdf2links.compare``'s own formatting and figures.
"""
