"""Write meshes/cube.stl (ASCII), meshes/cube.obj and meshes/cube.dae: a unit cube,
corners at +-0.5."""
import numpy as np

V = [(x, y, z) for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)]
FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
TRIS = [t for a, b, c, d in FACES for t in ((a, b, c), (a, c, d))]


def normal(t):
    p = [np.array(V[i]) for i in t]
    v = np.cross(p[1] - p[0], p[2] - p[0])
    return v / np.linalg.norm(v)


with open('meshes/cube.stl', 'w') as f:
    f.write('solid cube\n')
    for t in TRIS:
        f.write(' facet normal %g %g %g\n  outer loop\n' % tuple(normal(t)))
        for i in t:
            f.write('   vertex %g %g %g\n' % V[i])
        f.write('  endloop\n endfacet\n')
    f.write('endsolid cube\n')
with open('meshes/cube.obj', 'w') as f:
    f.write('# unit cube\n')
    for v in V:
        f.write('v %g %g %g\n' % v)
    for t in TRIS:
        f.write('f %d %d %d\n' % tuple(i + 1 for i in t))

# meshes/cube.dae: the same cube as COLLADA 1.4 (one triangle list, metres, Z up as
# ROS meshes are), for three.js' ColladaLoader.
positions = ' '.join('%g %g %g' % v for v in V)
indices = ' '.join('%d' % i for t in TRIS for i in t)
with open('meshes/cube.dae', 'w') as f:
    f.write('''<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>
    <geometry id="cube" name="cube">
      <mesh>
        <source id="cube-positions">
          <float_array id="cube-positions-array" count="%d">%s</float_array>
          <technique_common>
            <accessor source="#cube-positions-array" count="%d" stride="3">
              <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="cube-vertices"><input semantic="POSITION" source="#cube-positions"/></vertices>
        <triangles count="%d"><input semantic="VERTEX" source="#cube-vertices" offset="0"/><p>%s</p></triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
      <node id="cube-node" name="cube"><instance_geometry url="#cube"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
''' % (3 * len(V), positions, len(V), len(TRIS), indices))
