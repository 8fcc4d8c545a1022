// A slab of thickness t of the quarter ring a <= r <= b (meshes/quarter_ring.geo extruded
// along z), for the 3D elasto-plastic solver (tests/fem/test_plastic_3d.py): with u_z = 0
// on both faces it is the plane strain opening of docs/plasticity.md. Surfaces: the inner
// wall "wall", the outer boundary "outer", the symmetry planes "bottom" (y = 0) and
// "left" (x = 0), the faces "back" (z = 0) and "front" (z = t); the volume "rock".
// Second-order (curved) tetrahedra; the size is h at the wall and grows with r to h b/a.
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  b = {10.0, Name "Parameters/b"},
  h = {0.3, Name "Parameters/h"},
  t = {0.3, Name "Parameters/t"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {a, 0, 0, h};
Point(3) = {b, 0, 0, h * b / a};
Point(4) = {0, b, 0, h * b / a};
Point(5) = {0, a, 0, h};
Line(1) = {2, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 5};
Circle(4) = {5, 1, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude {0, 0, t} { Surface{1}; };
// out[0] the top face, out[1] the volume, out[2..5] the faces swept by lines 1..4.
Physical Surface("back") = {1};
Physical Surface("front") = {out[0]};
Physical Surface("bottom") = {out[2]};
Physical Surface("outer") = {out[3]};
Physical Surface("left") = {out[4]};
Physical Surface("wall") = {out[5]};
Physical Volume("rock") = {out[1]};
Mesh.ElementOrder = 2;
Mesh.HighOrderOptimize = 1;
