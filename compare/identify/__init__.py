"""``urdf2links identify DESCRIPTION --against OTHER``: which of a description's numbers must change for it to move
as a second description does in MuJoCo (docs/identify.md, "The command").

- :mod:`.excitation`: the excitation trajectories (periodic Fourier series within the joint limits) and the
  ``--design`` search that lowers the condition number of the base regressor;
- :mod:`.recording`: OTHER run by MuJoCo, servoed along those trajectories with known applied torques; its
  ``qpos``, ``qvel``, ``qacc`` and forces mapped to DESCRIPTION's coordinates;
- :mod:`.fitting`: the library's regressor (:mod:`urdf2links.identification`) fed with those samples; the
  parameter table;
- :mod:`.validation`: a held-out seed, simulated with the description and with the identified model, both engines;
- :mod:`.writers`: the corrected URDF / MJCF, every change listed;
- :mod:`.report`: report.html, identify.json, identify.md and the figures;
- :mod:`.command`: the command's handler.
"""
