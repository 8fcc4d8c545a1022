// hostile: nx_1e20 (must be refused before gmsh runs it)
DefineConstant[ nx = {4, Name "Parameters/nx"}, h = {0.5, Min 0.1, Max 1, Name "Parameters/h"} ];
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Physical Surface("domain") = {1};
Physical Curve("left") = {4};
