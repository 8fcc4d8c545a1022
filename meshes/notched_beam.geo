// Notched three-point beam after Galvez et al. (seed thesis, section 2.4.3): a beam of length
// 675 mm (-337.5 <= x <= 337.5) and depth 150 mm (0 <= y <= 150), centre x = 0, with a
// zero-width notch from (0, 0) to (0, a) modelled as an embedded line (element edges follow
// it; nodes on it are shared). Point supports on the bottom edge at x = -75 (roller) and
// x = +300 (pin), point load on the top edge at x = +150. The mesh is refined to h_fine in
// the box -40 <= x <= 120 (right of the notch, where the crack runs) with a smooth
// transition to h elsewhere. Defaults give 7,806 nodes and 15,313 triangles (seed: 7,863 nodes).
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {75, Name "Parameters/a"},
  h = {12, Name "Parameters/h"},
  h_fine = {2.2, Name "Parameters/h_fine"},
  transition = {100, Name "Parameters/transition"}
];

L = 675;
D = 150;

// bottom edge, left to right
Point(1) = {-L/2, 0, 0};
Point(2) = {-75, 0, 0};   // roller support
Point(3) = {0, 0, 0};     // notch mouth
Point(4) = {300, 0, 0};   // pin support
Point(5) = {L/2, 0, 0};
// top edge, right to left
Point(6) = {L/2, D, 0};
Point(7) = {150, D, 0};   // load
Point(8) = {-L/2, D, 0};
// notch tip
Point(9) = {0, a, 0};

Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // bottom
Line(3) = {3, 4};  // bottom
Line(4) = {4, 5};  // bottom
Line(5) = {5, 6};  // right
Line(6) = {6, 7};  // top
Line(7) = {7, 8};  // top
Line(8) = {8, 1};  // left
Line(9) = {3, 9};  // notch
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8};
Plane Surface(1) = {1};
Curve{9} In Surface{1};

// mesh size: h_fine inside the box, growing linearly to h over `transition` mm outside it
Field[1] = Box;
Field[1].VIn = h_fine;
Field[1].VOut = h;
Field[1].XMin = -40;
Field[1].XMax = 120;
Field[1].YMin = 0;
Field[1].YMax = D;
Field[1].Thickness = transition;
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Surface("domain") = {1};
Physical Curve("notch") = {9};
Physical Curve("bottom") = {1, 2, 3, 4};
Physical Curve("right") = {5};
Physical Curve("top") = {6, 7};
Physical Curve("left") = {8};
Physical Point("support_roller") = {2};
Physical Point("support_pin") = {4};
Physical Point("load") = {7};
