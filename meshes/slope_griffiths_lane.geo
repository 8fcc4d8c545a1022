// The homogeneous slope of Griffiths and Lane (1999), example 1 (their Fig. 3 with no
// foundation layer, D = 1): height H, slope horizontal:vertical = n:1 (n = 2: 26.57
// degrees), the toe at the origin on the firm base y = 0, the crest at (n H, H) and the
// level ground behind it out to x = n H + L. For the strength-reduction factor of safety
// (geofrac/fem/strength_reduction.py, docs/plasticity.md): the base "base" (y = 0,
// fixed), the back "back" (x = n H + L, rollers), the free faces "face" (the slope) and
// "crest" (the level top), the cells "soil". Mesh size h, 6-node triangles; the gmsh
// Mesh.Algorithm from the parameter (6 frontal-Delaunay, 5 Delaunay, 1 MeshAdapt; a
// scene's geometry.algorithm overrides it).
DefineConstant[
  H = {10.0, Name "Parameters/H"},
  n = {2.0, Name "Parameters/n"},
  L = {12.0, Name "Parameters/L"},
  h = {1.0, Name "Parameters/h"},
  algorithm = {6, Name "Parameters/algorithm"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {n * H + L, 0, 0, h};
Point(3) = {n * H + L, H, 0, h};
Point(4) = {n * H, H, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Curve("base") = {1};
Physical Curve("back") = {2};
Physical Curve("crest") = {3};
Physical Curve("face") = {4};
Physical Surface("soil") = {1};
Mesh.Algorithm = algorithm;
Mesh.ElementOrder = 2;
