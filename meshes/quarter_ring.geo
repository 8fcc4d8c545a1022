// A quarter of a thick ring a <= r <= b (a circular opening of radius a in a ring of
// outer radius b), for the elasto-plastic opening (tests/fem/test_plastic.py, docs/plasticity.md):
// the inner wall "wall", the outer boundary "outer", the symmetry lines "bottom" (y = 0)
// and "left" (x = 0), the cells "rock". Curved (second-order) cells; the mesh size is
// h at the wall and grows geometrically with r to h * b/a at the outer boundary
// (about the same number of cells per ring of constant r2/r1).
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  b = {20.0, Name "Parameters/b"},
  h = {0.1, Name "Parameters/h"}
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
Physical Curve("bottom") = {1};
Physical Curve("outer") = {2};
Physical Curve("left") = {3};
Physical Curve("wall") = {4};
Physical Surface("rock") = {1};
Mesh.ElementOrder = 2;
Mesh.HighOrderOptimize = 1;
