// Cook's membrane (Cook 1974): the tapered panel with corners (0, 0), (48, 44), (48, 60),
// (0, 44), clamped on its left edge x = 0 and sheared on its right edge x = 48. A classic
// test of volumetric locking in plane strain (docs/stability.md, "Locking").
// Meshed as n x n quadrilaterals, each split into two triangles.
DefineConstant[
  n = {16, Min 1, Max 512, Step 1, Name "Parameters/n"}
];

Point(1) = {0, 0, 0};
Point(2) = {48, 44, 0};
Point(3) = {48, 60, 0};
Point(4) = {0, 44, 0};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // loaded edge x = 48
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // clamped edge x = 0
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Transfinite Curve{1, 2, 3, 4} = n + 1;
Transfinite Surface{1} = {1, 2, 3, 4};

Physical Surface("domain") = {1};
Physical Curve("clamped") = {4};
Physical Curve("loaded") = {2};
Physical Curve("top") = {3};
Physical Curve("bottom") = {1};
Physical Point("tip") = {3};
