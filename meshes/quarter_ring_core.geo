// The quarter ring of meshes/quarter_ring.geo with its core 0 <= r <= a meshed too, for
// the excavation of a circular opening in stages (jobs/tunnel_excavation_mohr_coulomb.toml,
// tests/fem/test_plastic_stages.py): the cells "core" (r <= a, removed by a stage) and
// "rock" (a <= r <= b), the interface "wall" (r = a), the outer boundary "outer", the
// symmetry lines "bottom" (y = 0) and "left" (x = 0), both through the core and the rock.
// Curved (second-order) cells; the size is h at the wall, 2 h at the centre, and grows
// geometrically with r to h * b/a at the outer boundary.
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  b = {20.0, Name "Parameters/b"},
  h = {0.1, Name "Parameters/h"}
];
Point(1) = {0, 0, 0, 2 * h};
Point(2) = {a, 0, 0, h};
Point(3) = {b, 0, 0, h * b / a};
Point(4) = {0, b, 0, h * b / a};
Point(5) = {0, a, 0, h};
Line(1) = {2, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 5};
Circle(4) = {5, 1, 2};
Line(5) = {1, 2};
Line(6) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {5, -4, 6};
Plane Surface(2) = {2};
Physical Curve("bottom") = {1, 5};
Physical Curve("outer") = {2};
Physical Curve("left") = {3, 6};
Physical Curve("wall") = {4};
Physical Surface("rock") = {1};
Physical Surface("core") = {2};
Mesh.ElementOrder = 2;
Mesh.HighOrderOptimize = 1;
