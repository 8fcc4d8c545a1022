// Patch test square with an MLS core (Edo (2016), §2.4.2, Fig. 2.9): a square
// a x a (a = 5 mm, 0 <= x, y <= a) containing a square core of side b centred at
// (a/2, a/2) whose four edges are embedded lines, so element edges follow the core
// boundary and every triangle lies either inside or outside the core. One plane surface
// ("domain") holds both. Uniform mesh size h. Values of h giving about Edo (2016)'s node
// counts (gmsh 4.15, default Frontal-Delaunay algorithm):
//   Edo (2016) |   h    | nodes | triangles
//          218 | 0.475  |   214 |       382
//          526 | 0.26   |   523 |       964
//        1,028 | 0.182  | 1,029 |     1,944
//        2,021 | 0.128  | 1,955 |     3,748
//        3,948 | 0.0904 | 3,994 |     7,762
//        9,857 | 0.056  | 9,608 |    18,854
// The count jumps where b/h crosses an integer (the core edges gain a segment), so 2,021
// and 9,857 fall in gaps: the next finer meshes, h = 0.1235 and 0.0552, give 2,227 and
// 10,168 nodes.
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {5, Name "Parameters/a"},
  b = {1, Name "Parameters/b"},
  h = {0.475, Name "Parameters/h"}
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

// core [a/2 - b/2, a/2 + b/2]^2
Point(5) = {0.5 * (a - b), 0.5 * (a - b), 0, h};
Point(6) = {0.5 * (a + b), 0.5 * (a - b), 0, h};
Point(7) = {0.5 * (a + b), 0.5 * (a + b), 0, h};
Point(8) = {0.5 * (a - b), 0.5 * (a + b), 0, h};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 5};
Curve{5, 6, 7, 8} In Surface{1};

Physical Surface("domain") = {1};
Physical Curve("boundary") = {1, 2, 3, 4};
Physical Curve("core") = {5, 6, 7, 8};
