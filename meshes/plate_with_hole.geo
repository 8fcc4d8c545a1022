// Quarter of a plate with a central circular hole, for the stress concentration factor
// (jobs/plate_hole_elastic.toml). The plate is 2W wide and 2H high with a hole of radius a
// at the origin; the quarter x >= 0, y >= 0 is meshed, with the symmetry lines x = 0
// ("left") and y = 0 ("bottom"). The mesh size is h_hole on the hole and grows linearly
// with the distance from it to h_far at 5a and beyond. Parameters come from a scene's
// [geometry.parameters]; units are the scene's.
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  W = {10.0, Name "Parameters/W"},
  H = {30.0, Name "Parameters/H"},
  h_hole = {0.05, Name "Parameters/h_hole"},
  h_far = {1.0, Name "Parameters/h_far"}
];

Point(1) = {0, 0, 0, h_hole};  // hole centre (not meshed)
Point(2) = {a, 0, 0, h_hole};  // hole edge on the x axis: the peak of σyy under σ along y
Point(3) = {W, 0, 0, h_far};
Point(4) = {W, H, 0, h_far};
Point(5) = {0, H, 0, h_far};
Point(6) = {0, a, 0, h_hole};  // hole edge on the y axis

Line(1) = {2, 3};        // bottom (y = 0)
Line(2) = {3, 4};        // right (x = W)
Line(3) = {4, 5};        // top (y = H)
Line(4) = {5, 6};        // left (x = 0)
Circle(5) = {6, 1, 2};   // hole

Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Field[1] = Distance;
Field[1].CurvesList = {5};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_hole;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = 5 * a;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("domain") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("hole") = {5};
