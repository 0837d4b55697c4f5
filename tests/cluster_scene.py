"""A small scene for the distributed-rendering tests: a quad (an OBJ file, so shipping and shared files
both matter) and a sphere under ambient occlusion, noisy enough that a wrong sample range shows."""
from pathlib import Path

OBJ = """v -2 -1 -1
v 2 -1 -1
v 2 -1 3
v -2 -1 3
f 1 2 3 4
"""


def write_scene(folder, width=40, height=30, spp=8, integrator="ao") -> Path:
    """(A point light as well, for the integrators that need one; ao ignores it.)"""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "floor.obj").write_text(OBJ)
    p = folder / "scene.xml"
    p.write_text(f"""<?xml version="1.0"?>
<scene>
  <default name="w" value="{width}"/>
  <integrator type="{integrator}"/>
  <sampler type="independent"><integer name="sampleCount" value="{spp}"/></sampler>
  <camera type="perspective">
    <integer name="width" value="$w"/><integer name="height" value="{height}"/><float name="fov" value="50"/>
    <transform name="toWorld"><lookat origin="0,1,5" target="0,-0.5,0" up="0,1,0"/></transform>
  </camera>
  <mesh type="obj"><string name="filename" value="floor.obj"/><bsdf type="diffuse"/></mesh>
  <mesh type="sphere"><point name="center" value="0,-0.3,0.5"/><float name="radius" value="0.7"/>
    <bsdf type="diffuse"/></mesh>
  <emitter type="point"><point name="position" value="1,2,2"/><color name="power" value="40,40,40"/></emitter>
</scene>""")
    return p
