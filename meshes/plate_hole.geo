// Plate with a circular hole in uniaxial compression after Tang et al. (Edo (2016), §2.4.4):
// a plate of width W = 50 mm (0 <= x <= 50) and height H = 170 mm (0 <= y <= 170) with a
// hole of diameter d = 20 mm centred at (25, 85), loaded on the top edge and supported on
// the bottom edge. The hole is four quarter arcs whose end points include its top (25, 95)
// and bottom (25, 75), where cracks initiate. Uniform mesh size h; the default gives
// 12,887 nodes and 25,196 triangles (Edo (2016): 12,933 nodes, 25,448 elements); gmsh also keeps
// a node at the hole centre (the arcs' centre point), which no element uses.
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  h = {0.873, Name "Parameters/h"}
];

W = 50;
H = 170;
r = 10;
xc = 25;
yc = 85;

Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, H, 0, h};
Point(4) = {0, H, 0, h};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // right
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // left

Point(5) = {xc, yc, 0, h};      // hole centre (not meshed)
Point(6) = {xc + r, yc, 0, h};  // hole right
Point(7) = {xc, yc + r, 0, h};  // hole top
Point(8) = {xc - r, yc, 0, h};  // hole left
Point(9) = {xc, yc - r, 0, h};  // hole bottom
Circle(5) = {6, 5, 7};
Circle(6) = {7, 5, 8};
Circle(7) = {8, 5, 9};
Circle(8) = {9, 5, 6};

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};

Physical Surface("domain") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("hole") = {5, 6, 7, 8};
Physical Point("bottom_left") = {1};
