"""Small MJCF files for the MJCF tests, one per element and attribute the reader must resolve as MuJoCo does.

Each is text (``MODELS[name]``); :func:`write_models` writes them, with the included file of
``include_defaults``, into a folder. Every body that moves has mass; the numbers are arbitrary but
not special (axes off the coordinate axes, anchors off the body origin, non-zero ``ref``).
"""

from __future__ import annotations

from pathlib import Path

MODELS = {
    # a hinge about a skew axis through an anchor off the body's origin, ref != 0, angles in degrees,
    # euler body orientation; armature, damping, stiffness at a springref
    "hinge_anchor": """<mujoco model="hinge_anchor">
  <compiler angle="degree"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="arm" pos="0.1 -0.2 0.5" euler="10 20 30">
      <joint name="h" type="hinge" axis="1 2 0.5" pos="0.05 0.1 -0.2" ref="25" armature="0.05" damping="0.3"
             stiffness="2" springref="40"/>
      <geom type="capsule" fromto="0 0 0 0.4 0.1 -0.3" size="0.04" density="900"/>
      <body name="tip" pos="0.4 0.1 -0.3" quat="0.9 0.1 0.3 -0.2">
        <joint name="h2" type="hinge" axis="0 1 0" pos="0 0 0.05" armature="0.01"/>
        <geom type="box" size="0.05 0.1 0.02" pos="0.1 0 0" mass="0.4"/>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # several joints in one body: a slide and two hinges with different axes and anchors, a skew slide
    "multi_joint": """<mujoco model="multi_joint">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="carriage" pos="0 0 1" quat="0.7 0.2 -0.1 0.3">
      <joint name="s1" type="slide" axis="0.3 1 0.2" ref="0.1" armature="0.2" damping="0.5"/>
      <joint name="h1" type="hinge" axis="0 0 1" pos="0.1 0 0" ref="0.3"/>
      <joint name="h2" type="hinge" axis="1 1 0" pos="0 0.2 0.1" armature="0.03" stiffness="1" springref="-0.2"/>
      <inertial pos="0.1 0.05 -0.02" mass="1.5" fullinertia="0.02 0.03 0.025 0.001 -0.002 0.003"/>
      <body name="rod" pos="0.3 0 0">
        <joint name="s2" type="slide" axis="1 0 0"/>
        <geom type="cylinder" size="0.03 0.2" mass="0.6"/>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # a ball joint about an anchor off the origin (armature on its three dofs), a hinge below it
    "ball": """<mujoco model="ball">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="upper" pos="0 0 1.5" euler="0.3 -0.2 0.5">
      <joint name="shoulder" type="ball" pos="0 0 0.1" armature="0.02"/>
      <geom type="capsule" fromto="0 0 0 0.05 0.1 -0.6" size="0.05"/>
      <body name="lower" pos="0.05 0.1 -0.6">
        <joint name="elbow" type="hinge" axis="1 0 0.2" armature="0.01" damping="0.05"/>
        <geom type="capsule" fromto="0 0 0 0 0.2 -0.4" size="0.04"/>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # a free body (armature on its six dofs) with a hinged flap, gravcomp on the flap, gravity askew
    "free": """<mujoco model="free">
  <option gravity="3 0 -8"/>
  <worldbody>
    <body name="hull" pos="0.2 0.3 2" quat="0.8 0.2 0.4 0.4">
      <joint name="root" type="free" armature="0.1"/>
      <geom type="box" size="0.3 0.2 0.1" density="500"/>
      <body name="flap" pos="0.3 0 0" gravcomp="0.4">
        <joint name="flap" type="hinge" axis="0 1 0" pos="-0.05 0 0" damping="0.2"/>
        <geom type="box" size="0.1 0.15 0.01" pos="0.1 0 0" mass="0.3"/>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # two trees under the world, a body without joints welded to its parent, a mocap body, and a
    # freejoint (the shortcut: no armature or damping)
    "two_trees": """<mujoco model="two_trees">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="mocap" mocap="true" pos="1 1 1"><geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body>
    <body name="base" pos="0 0 0.5">
      <geom type="box" size="0.1 0.1 0.1"/>
      <body name="link1" pos="0 0 0.1">
        <joint name="j1" type="hinge" axis="0 0 1"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <body name="weld" pos="0.3 0 0" euler="0.1 0.2 0.3">
          <geom type="sphere" size="0.06" pos="0.05 0 0"/>
        </body>
      </body>
    </body>
    <body name="ball2" pos="1 0 1">
      <freejoint name="float"/>
      <geom type="ellipsoid" size="0.1 0.2 0.3"/>
    </body>
  </worldbody>
</mujoco>""",
    # fusestatic: the static bodies are fused into their parents by MuJoCo's compiler
    "fusestatic": """<mujoco model="fusestatic">
  <compiler fusestatic="true"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <geom type="box" size="0.1 0.05 0.05" pos="0.1 0 0"/>
      <body name="static" pos="0.2 0 0" euler="0 0.5 0">
        <geom type="sphere" size="0.05" pos="0.05 0 0"/>
        <body name="b" pos="0.1 0 0">
          <joint name="jb" type="hinge" axis="1 0 0"/>
          <geom type="box" size="0.05 0.1 0.02"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # everything the tree does not use, each to be named in the notes
    "everything_else": """<mujoco model="everything_else">
  <option gravity="0 0 -9.81" density="1.2" viscosity="0.01"/>
  <default><joint damping="0.1"/></default>
  <worldbody>
    <light pos="0 0 3"/>
    <camera name="cam" pos="0 -2 1"/>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0" limited="true" range="-1 1" frictionloss="0.2"/>
      <geom name="ga" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
      <site name="sa" pos="0.3 0 0"/>
      <body name="b" pos="0.3 0 0">
        <joint name="jb" type="hinge" axis="0 1 0"/>
        <geom name="gb" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <site name="sb" pos="0.3 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon><spatial name="t" stiffness="10" damping="1"><site site="sa"/><site site="sb"/></spatial></tendon>
  <equality><joint joint1="ja" joint2="jb"/></equality>
  <contact><pair geom1="ga" geom2="gb"/></contact>
  <actuator><motor name="m" joint="ja"/></actuator>
  <sensor><jointpos joint="ja"/></sensor>
  <keyframe><key name="home" qpos="0.1 0.2"/></keyframe>
</mujoco>""",
    # includes and defaults classes: the included file holds the default classes the bodies use
    "include_defaults": """<mujoco model="include_defaults">
  <include file="include_defaults_classes.xml"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a" pos="0 0 1" childclass="arm">
      <joint name="ja" axis="0 1 0"/>
      <geom fromto="0 0 0 0.3 0 0"/>
      <body name="b" pos="0.3 0 0">
        <joint name="jb" class="stiff" axis="1 0 0"/>
        <geom fromto="0 0 0 0 0 -0.3"/>
      </body>
    </body>
  </worldbody>
</mujoco>""",
    # the file's own <flag>s: gravity and dampers off (the default scene follows them)
    "flags": """<mujoco model="flags">
  <option gravity="0 0 -9.81"><flag gravity="disable" damper="disable"/></option>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0" damping="3" stiffness="2"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
    </body>
  </worldbody>
</mujoco>""",
}

#: Files the models include, by name.
INCLUDED = {
    "include_defaults_classes.xml": """<mujoco>
  <default>
    <default class="arm">
      <joint type="hinge" armature="0.04" damping="0.2"/>
      <geom type="capsule" size="0.03" density="1500"/>
      <default class="stiff"><joint stiffness="3" springref="0.5"/></default>
    </default>
  </default>
</mujoco>""",
}


def write_models(folder: Path) -> dict[str, Path]:
    """Write every model (and the files they include) into ``folder``; ``{name: path}``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in INCLUDED.items():
        (folder / name).write_text(text)
    out = {}
    for name, text in MODELS.items():
        out[name] = folder / f"{name}.xml"
        out[name].write_text(text)
    return out
