// A square block [-L/2, L/2]² with a circular opening of radius a at its centre, meshed
// whole (tests/fracture/test_staged_cracking.py, jobs/tunnel_staged_cracking.toml). The opening's
// interior is the cell group "hole" (removed by a stage), or with split = 1 its upper half
// "heading" and lower half "bench" (two stages), the rest "rock"; the sides
// are "left", "right", "bottom", "top". Straight cells. The mesh size is h_wall on the
// wall and grows linearly with the distance from it to h_far at 4a and beyond.
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  L = {12.0, Name "Parameters/L"},
  h_wall = {0.1, Name "Parameters/h_wall"},
  h_far = {1.5, Name "Parameters/h_far"},
  split = {0, Name "Parameters/split"}
];

Point(1) = {0, 0, 0, h_wall};
Point(2) = {a, 0, 0, h_wall};
Point(3) = {0, a, 0, h_wall};
Point(4) = {-a, 0, 0, h_wall};
Point(5) = {0, -a, 0, h_wall};
Point(6) = {-L/2, -L/2, 0, h_far};
Point(7) = {L/2, -L/2, 0, h_far};
Point(8) = {L/2, L/2, 0, h_far};
Point(9) = {-L/2, L/2, 0, h_far};

Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Line(5) = {6, 7};
Line(6) = {7, 8};
Line(7) = {8, 9};
Line(8) = {9, 6};

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2, 1};
If (split == 0)
  Plane Surface(1) = {1};
Else
  Line(9) = {2, 4};  // the opening's horizontal diameter
  Curve Loop(3) = {1, 2, -9};
  Plane Surface(1) = {3};  // upper half: the heading
  Curve Loop(4) = {3, 4, 9};
  Plane Surface(3) = {4};  // lower half: the bench
EndIf

Field[1] = Distance;
Field[1].CurvesList = {1, 2, 3, 4};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_wall;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = 4 * a;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("rock") = {2};
If (split == 0)
  Physical Surface("hole") = {1};
Else
  Physical Surface("heading") = {1};
  Physical Surface("bench") = {3};
EndIf
Physical Curve("bottom") = {5};
Physical Curve("right") = {6};
Physical Curve("top") = {7};
Physical Curve("left") = {8};
Physical Curve("wall") = {1, 2, 3, 4};
