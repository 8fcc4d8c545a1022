// Notched three-point beam after Galvez et al. (Edo (2016), §2.4.3): a beam of length
// 675 mm (-337.5 <= x <= 337.5) and depth 150 mm (0 <= y <= 150), centre x = 0, with a
// sawn notch of depth a and width w centred on x = 0: a slot in the geometry with free
// faces (Edo (2016) and Galvez et al. do not give the width; 2 mm is assumed); w = 0 gives
// an embedded line instead (see below). A zero-width
// notch of cracked edges would leave the notch closed: nodes on it are shared, and intact
// cells touching it only at a vertex tie its two faces together. Point supports on the
// bottom edge at x = -75 (roller) and x = +300 (pin), point load on the top edge at
// x = +150. The mesh is refined to h_fine in the box -40 <= x <= 120 (right of the notch,
// where the crack runs) with a smooth transition to h elsewhere. Defaults give about
// 7,800 nodes (Edo (2016): 7,863).
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {75, Name "Parameters/a"},
  w = {2, Name "Parameters/w"},
  h = {12, Name "Parameters/h"},
  h_fine = {2.2, Name "Parameters/h_fine"},
  transition = {100, Name "Parameters/transition"},
  algorithm = {6, Name "Parameters/algorithm"}  // gmsh Mesh.Algorithm: 6 frontal-Delaunay, 5 Delaunay, 1 MeshAdapt
];

L = 675;
D = 150;

If (w > 0)
// bottom edge, left to right
Point(1) = {-L/2, 0, 0};
Point(2) = {-75, 0, 0};   // roller support
Point(3) = {-w/2, 0, 0};  // notch mouth, left
Point(10) = {w/2, 0, 0};  // notch mouth, right
Point(4) = {300, 0, 0};   // pin support
Point(5) = {L/2, 0, 0};
// top edge, right to left
Point(6) = {L/2, D, 0};
Point(7) = {150, D, 0};   // load
Point(8) = {-L/2, D, 0};
// notch tip corners
Point(9) = {-w/2, a, 0};
Point(11) = {w/2, a, 0};

Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // bottom
Line(3) = {10, 4}; // bottom
Line(4) = {4, 5};  // bottom
Line(5) = {5, 6};  // right
Line(6) = {6, 7};  // top
Line(7) = {7, 8};  // top
Line(8) = {8, 1};  // left
Line(9) = {11, 10};  // notch, right face (downwards)
Line(10) = {9, 11};  // notch tip
Line(11) = {3, 9};   // notch, left face
Curve Loop(1) = {1, 2, 11, 10, 9, 3, 4, 5, 6, 7, 8};
Plane Surface(1) = {1};
notch[] = {9, 10, 11};
Else
// w = 0: the notch is a line embedded in the mesh (element edges follow it, its nodes are
// shared by both sides), for models that crack it before loading (grain interfaces)
Point(1) = {-L/2, 0, 0};
Point(2) = {-75, 0, 0};   // roller support
Point(3) = {0, 0, 0};     // notch mouth
Point(4) = {300, 0, 0};   // pin support
Point(5) = {L/2, 0, 0};
Point(6) = {L/2, D, 0};
Point(7) = {150, D, 0};   // load
Point(8) = {-L/2, D, 0};
Point(9) = {0, a, 0};     // notch tip

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
Line{9} In Surface{1};
notch[] = {9};
EndIf

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
Mesh.Algorithm = algorithm;

Physical Surface("domain") = {1};
Physical Curve("notch") = {notch[]};
Physical Curve("bottom") = {1, 2, 3, 4};
Physical Curve("right") = {5};
Physical Curve("top") = {6, 7};
Physical Curve("left") = {8};
Physical Point("support_roller") = {2};
Physical Point("support_pin") = {4};
Physical Point("load") = {7};
