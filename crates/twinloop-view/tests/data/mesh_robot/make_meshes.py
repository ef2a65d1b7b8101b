"""Write meshes/cube.stl (ASCII) and meshes/cube.obj: a unit cube, corners at +-0.5."""
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
