// Square a x a with an unstructured (Delaunay) triangle mesh of size h.
// Patch test of Edo (2016), §2.4.2, Fig. 2.9: a = 5 mm, u = 0.002 x, v = -0.0006 y on the boundary.
DefineConstant[
  a = {5, Name "Parameters/a"},
  h = {0.5, Name "Parameters/h"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {a, 0, 0, h};
Point(3) = {a, a, 0, h};
Point(4) = {0, a, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Surface("domain") = {1};
Physical Curve("boundary") = {1, 2, 3, 4};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
