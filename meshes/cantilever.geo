// Timoshenko cantilever (Edo (2016), §2.4.1, Fig. 2.7; §3.3.1, Fig. 3.9).
// Beam 0 <= x <= L, -D/2 <= y <= D/2 meshed with nx x ny squares, each split into two
// right-isosceles triangles when L/nx == D/ny (the meshes of Edo (2016): 4x40 ... 11x110, ny x nx).
// Parameters are overridden from a scene's [geometry.parameters] (gmsh -setnumber).
DefineConstant[
  L = {10, Name "Parameters/L"},
  D = {1, Name "Parameters/D"},
  nx = {40, Name "Parameters/nx"},
  ny = {4, Name "Parameters/ny"}
];

Point(1) = {0, -D/2, 0};
Point(2) = {L, -D/2, 0};
Point(3) = {L,  D/2, 0};
Point(4) = {0,  D/2, 0};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // loaded end x = L
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // fixed end x = 0
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} = {1, 2, 3, 4} Right;

Physical Surface("domain") = {1};
Physical Curve("fixed") = {4};
Physical Curve("tip") = {2};
Physical Curve("top") = {3};
Physical Curve("bottom") = {1};
