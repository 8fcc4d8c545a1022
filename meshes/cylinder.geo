// Cylinder of radius r and height l on the z axis, tetrahedral mesh of size h: the block
// model of Edo (2016), Fig. 5.10 (a cylinder turned into 3D blocks). Parameters come from a
// scene's [geometry.parameters].
SetFactory("OpenCASCADE");
DefineConstant[
  r = {0.5, Name "Parameters/r"},
  l = {2, Name "Parameters/l"},
  h = {0.1, Name "Parameters/h"}
];
Cylinder(1) = {0, 0, 0, 0, 0, l, r};
MeshSize{ PointsOf{ Volume{1}; } } = h;
Mesh.MeshSizeMax = h;
Physical Volume("domain") = {1};
Physical Surface("boundary") = {1, 2, 3};
