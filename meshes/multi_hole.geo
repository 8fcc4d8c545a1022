// Plate with 1, 3 or 5 circular holes under uniaxial compression (Edo (2016), §3.5.2,
// Fig. 3.17-3.18, after Tang et al.): 100 mm wide (0 <= x <= 100) and 200 mm long
// (0 <= y <= 200), loaded along y. The hole centres and diameters of Edo (2016) are in its
// Fig. 3.17, which the text does not reproduce; ours: a large hole (diameter 20 mm) at
// the centre, for n = 3 two holes of 12 mm at (30, 60) and (70, 140), for n = 5 also two
// of 8 mm at (72, 68) and (28, 132) - the holes lie on a diagonal band so that cracks from
// one can run to the next. Uniform mesh size h (Edo (2016): uniform; 7,197 / 6,112 / 5,521
// nodes). Units: mm. Parameters come from a scene's [geometry.parameters].
SetFactory("OpenCASCADE");
DefineConstant[
  n = {1, Name "Parameters/n"},
  h = {2.0, Name "Parameters/h"}
];

W = 100;
L = 200;
Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, L, 0, h};
Point(4) = {0, L, 0, h};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // right
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // left
Curve Loop(1) = {1, 2, 3, 4};

cx[] = {50, 30, 70, 72, 28};
cy[] = {100, 60, 140, 68, 132};
r[] = {10, 6, 6, 4, 4};
loops[] = {1};
For k In {0 : n - 1}
  c = newc;
  Circle(c) = {cx[k], cy[k], 0, r[k]};
  MeshSize{PointsOf{Curve{c};}} = h;
  l = newcl;
  Curve Loop(l) = {c};
  loops[] += {l};
  holes[] += {c};
EndFor
Plane Surface(1) = {loops[]};
Mesh.MeshSizeMax = h;

Physical Surface("domain") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("holes") = {holes[]};
Physical Point("bottom_left") = {1};
