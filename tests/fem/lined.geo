// A lined circular opening, a quarter model (tests/fem/test_insitu.py): the core r < b,
// the lining ring b < r < a and the rock of a square block of side L, each a cell
// group ("core", "ring", "rock"); symmetry lines "left" (x = 0) and "bottom" (y = 0)
// through all three; far sides "right" and "top". Curved (second-order) cells (order = 1:
// straight, for the cracking elements); the mesh
// size is h near the opening and grows to h_far at 10a.
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  b = {0.9, Name "Parameters/b"},
  L = {40.0, Name "Parameters/L"},
  h = {0.05, Name "Parameters/h"},
  h_far = {2.0, Name "Parameters/h_far"},
  order = {2, Name "Parameters/order"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {b, 0, 0, h};
Point(3) = {a, 0, 0, h};
Point(4) = {L, 0, 0, h_far};
Point(5) = {L, L, 0, h_far};
Point(6) = {0, L, 0, h_far};
Point(7) = {0, a, 0, h};
Point(8) = {0, b, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 1};
Circle(9) = {2, 1, 8};
Circle(10) = {3, 1, 7};
Curve Loop(1) = {1, 9, 8};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 10, 7, -9};
Plane Surface(2) = {2};
Curve Loop(3) = {3, 4, 5, 6, -10};
Plane Surface(3) = {3};
Field[1] = Distance;
Field[1].CurvesList = {10};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = 10 * a;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.ElementOrder = order;
Physical Surface("core") = {1};
Physical Surface("ring") = {2};
Physical Surface("rock") = {3};
Physical Curve("bottom") = {1, 2, 3};
Physical Curve("right") = {4};
Physical Curve("top") = {5};
Physical Curve("left") = {6, 7, 8};
Physical Curve("wall") = {10};
