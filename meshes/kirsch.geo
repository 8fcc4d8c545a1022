// Quarter of a square block with a circular opening of radius a at the origin, for the
// Kirsch problem (jobs/kirsch_stages.toml, docs/insitu.md). The block x, y in [0, L] is
// meshed whole: the opening's interior is the cell group "hole" (removed by a stage), the
// rest "rock". The symmetry lines are "left" (x = 0) and "bottom" (y = 0), each through
// both groups; "right" (x = L) and "top" (y = L) are the far sides; "wall" is the
// opening's boundary. The cells are curved (order = 2, second order) so the wall is a circle;
// order = 1 gives straight cells. The
// mesh size is h_wall on the wall and grows linearly with the distance from it to h_far
// at 10a and beyond. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {1.0, Name "Parameters/a"},
  L = {30.0, Name "Parameters/L"},
  h_wall = {0.05, Name "Parameters/h_wall"},
  h_far = {3.0, Name "Parameters/h_far"},
  order = {2, Name "Parameters/order"}
];

Point(1) = {0, 0, 0, h_wall};  // centre of the opening
Point(2) = {a, 0, 0, h_wall};  // sidewall (θ = 0)
Point(3) = {0, a, 0, h_wall};  // crown (θ = 90°)
Point(4) = {L, 0, 0, h_far};
Point(5) = {L, L, 0, h_far};
Point(6) = {0, L, 0, h_far};

Line(1) = {1, 2};        // bottom, inside the opening
Line(2) = {2, 4};        // bottom, rock
Line(3) = {4, 5};        // right
Line(4) = {5, 6};        // top
Line(5) = {6, 3};        // left, rock
Line(6) = {3, 1};        // left, inside the opening
Circle(7) = {2, 1, 3};   // wall

Curve Loop(1) = {1, 7, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, 5, -7};
Plane Surface(2) = {2};

Field[1] = Distance;
Field[1].CurvesList = {7};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_wall;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = 10 * a;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.ElementOrder = order;

Physical Surface("rock") = {2};
Physical Surface("hole") = {1};
Physical Curve("bottom") = {1, 2};
Physical Curve("right") = {3};
Physical Curve("top") = {4};
Physical Curve("left") = {5, 6};
Physical Curve("wall") = {7};
