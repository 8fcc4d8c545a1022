// Sneddon's penny-shaped crack (Sneddon, Proc. R. Soc. Lond. A 187, 1946): a crack of
// radius a in the plane z = 0 of a solid under remote tension normal to it. One quarter
// (x, y >= 0) of the block [-B, B]^2 x [-B, B] with the quarter crack as an internal
// surface: "symmetry_x" (x = 0) and "symmetry_y" (y = 0) carry the symmetry conditions,
// "bottom" (z = -B) and "top" (z = B) the far field; the far boundary is B from the
// crack's centre (B = 6a by default). Groups: "rock" (volume), "bottom", "top",
// "symmetry_x", "symmetry_y", "crack" (surfaces; the crack is cut when meshed:
// [plasticity.joints]). The size is h within 0.2 a of the crack, growing to hfar beyond
// 3a (a Distance/Threshold field). OpenCASCADE kernel; first-order tetrahedra.
// gmsh's 3D algorithm is the parameter algorithm3d (1 Delaunay, 4 Frontal, 10 HXT).
SetFactory("OpenCASCADE");
DefineConstant[
  a = {1, Name "Parameters/a"},
  B = {6, Name "Parameters/B"},
  h = {0.1, Name "Parameters/h"},
  hfar = {1.5, Name "Parameters/hfar"},
  algorithm3d = {1, Name "Parameters/algorithm3d"}
];
Box(1) = {0, 0, -B, B, B, 2 * B};
d = news; Disk(d) = {0, 0, 0, a};
q() = BooleanIntersection{ Surface{d}; Delete; }{ Volume{1}; };
BooleanFragments{ Volume{1}; Delete; }{ Surface{q()}; Delete; }
e = 1e-6 * B;
Physical Volume("rock") = Volume{:};
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -B - e, B + e, B + e, -B + e};
Physical Surface("top") = Surface In BoundingBox{-e, -e, B - e, B + e, B + e, B + e};
Physical Surface("symmetry_x") = Surface In BoundingBox{-e, -e, -B - e, e, B + e, B + e};
Physical Surface("symmetry_y") = Surface In BoundingBox{-e, -e, -B - e, B + e, e, B + e};
Physical Surface("crack") = Surface In BoundingBox{-e, -e, -e, a + e, a + e, e};
Field[1] = Distance;
Field[1].SurfacesList = {q()};
Field[1].Sampling = 40;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h;
Field[2].SizeMax = hfar;
Field[2].DistMin = 0.2 * a;
Field[2].DistMax = 3 * a;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = algorithm3d;  // 1 Delaunay, 4 Frontal, 10 HXT
