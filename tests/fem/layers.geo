// Two horizontal layers, for the geostatic initial stress tests (tests/fem/test_insitu.py):
// x in [0, W], "lower" y in [0, d] and "upper" y in [d, H]. Sides "left", "right",
// "bottom", "top"; each side group holds both layers' parts.
DefineConstant[
  W = {10.0, Name "Parameters/W"},
  H = {5.0, Name "Parameters/H"},
  d = {2.0, Name "Parameters/d"},
  h = {0.5, Name "Parameters/h"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, d, 0, h};
Point(4) = {W, H, 0, h};
Point(5) = {0, H, 0, h};
Point(6) = {0, d, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Line(7) = {6, 3};
Curve Loop(1) = {1, 2, -7, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {7, 3, 4, 5};
Plane Surface(2) = {2};
Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2, 3};
Physical Curve("top") = {4};
Physical Curve("left") = {5, 6};
