// Prandtl's strip footing (docs/plasticity.md, "Prandtl's strip footing"): the half
// domain right of the symmetry axis x = 0 of a strip footing of width B on a block of
// half-width W and depth D, the ground surface y = 0. The footing "footing" (0 <= x <=
// B/2 on y = 0), the free ground surface "surface" (B/2 <= x <= W), the symmetry axis
// "axis" (x = 0), the far side "side" (x = W), the base "base" (y = -D), the cells
// "soil". Mesh size hf at the footing's edge (B/2, 0), growing linearly with the
// distance from it to h at the distance r (the collapse mechanism of phi = 0 reaches
// B beyond the edge and B/sqrt(2) deep). 6-node triangles; the gmsh Mesh.Algorithm
// from the parameter (6 frontal-Delaunay, 5 Delaunay, 1 MeshAdapt; a scene's
// geometry.algorithm overrides it).
DefineConstant[
  B = {2.0, Name "Parameters/B"},
  W = {5.0, Name "Parameters/W"},
  D = {5.0, Name "Parameters/D"},
  h = {0.5, Name "Parameters/h"},
  hf = {0.05, Name "Parameters/hf"},
  r = {2.0, Name "Parameters/r"},
  algorithm = {6, Name "Parameters/algorithm"}
];
Point(1) = {0, 0, 0, h};
Point(2) = {B / 2, 0, 0, hf};
Point(3) = {W, 0, 0, h};
Point(4) = {W, -D, 0, h};
Point(5) = {0, -D, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Field[1] = Distance;
Field[1].PointsList = {2};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = h;
Field[2].DistMin = 0;
Field[2].DistMax = r;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Physical Curve("footing") = {1};
Physical Curve("surface") = {2};
Physical Curve("side") = {3};
Physical Curve("base") = {4};
Physical Curve("axis") = {5};
Physical Surface("soil") = {1};
Mesh.Algorithm = algorithm;
Mesh.ElementOrder = 2;
