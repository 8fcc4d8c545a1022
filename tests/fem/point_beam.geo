// Beam 0 <= x <= L, -D/2 <= y <= D/2 of nx x ny structured right triangles (ny even) with
// a physical point "tip" at the middle of the loaded end (L, 0), for point-load tests.
// "corners" holds two points (a point load on it is refused at run time).
DefineConstant[
  L = {10, Name "Parameters/L"},
  D = {1, Name "Parameters/D"},
  nx = {20, Name "Parameters/nx"},
  ny = {2, Name "Parameters/ny"}
];

Point(1) = {0, -D/2, 0};
Point(2) = {L, -D/2, 0};
Point(3) = {L, 0, 0};
Point(4) = {L, D/2, 0};
Point(5) = {0, D/2, 0};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // loaded end, lower half
Line(3) = {3, 4};  // loaded end, upper half
Line(4) = {4, 5};  // top
Line(5) = {5, 1};  // fixed end x = 0
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Transfinite Curve{1, 4} = nx + 1;
Transfinite Curve{2, 3} = ny / 2 + 1;
Transfinite Curve{5} = ny + 1;
Transfinite Surface{1} = {1, 2, 4, 5};

Physical Surface("domain") = {1};
Physical Curve("fixed") = {5};
Physical Curve("bottom") = {1};
Physical Curve("end") = {2, 3};
Physical Point("tip") = {3};
Physical Point("corners") = {2, 4};
