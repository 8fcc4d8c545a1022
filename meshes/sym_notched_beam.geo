// Symmetric notched three-point-bend beam, the mesh-dependence specimen of the cracking
// criterion (docs/cracking.md, geofrac bench mesh-dependence): a beam of length 440 mm
// (-220 <= x <= 220) and depth 100 mm (0 <= y <= 100) on a span of 400 mm: point supports
// on the bottom edge at x = -200 (pin) and x = +200 (roller). The load is a prescribed
// downward displacement of a pad of width `pad` on the top edge centred on x = 0 (physical
// curve "load"). A sawn notch of depth a and width w rises from the bottom on the axis
// x = 0; its faces are free and it ends in a right-angled V whose tip (0, a) is a mesh
// node on the axis. Everything is symmetric about x = 0, so the exact crack path is the
// axis: how far a computed path strays from it measures the mesh's pull on the crack.
// Mesh: h_fine in the band |x| < band (bottom to top), growing linearly to h over
// `transition` mm outside it; nothing in the mesh follows the axis (no embedded line).
// Defaults give 4,300-4,700 nodes by mesher. Units: mm. Parameters come from a scene's
// [geometry.parameters]; the mesher from its geometry.algorithm (which overrides
// Mesh.Algorithm set here).
DefineConstant[
  a = {50, Name "Parameters/a"},
  w = {2, Name "Parameters/w"},
  pad = {6, Name "Parameters/pad"},
  h = {10, Name "Parameters/h"},
  h_fine = {1.45, Name "Parameters/h_fine"},
  band = {25, Name "Parameters/band"},
  transition = {60, Name "Parameters/transition"}
];

L = 440;
S = 400;
D = 100;

// bottom edge, left to right, then the notch
Point(1) = {-L/2, 0, 0};
Point(2) = {-S/2, 0, 0};      // pin support
Point(3) = {-w/2, 0, 0};      // notch mouth, left
Point(4) = {-w/2, a - w/2, 0};  // start of the V, left
Point(5) = {0, a, 0};         // notch tip, on the axis
Point(6) = {w/2, a - w/2, 0};   // start of the V, right
Point(7) = {w/2, 0, 0};       // notch mouth, right
Point(8) = {S/2, 0, 0};       // roller support
Point(9) = {L/2, 0, 0};
// top edge, right to left
Point(10) = {L/2, D, 0};
Point(11) = {pad/2, D, 0};    // load pad, right end
Point(12) = {-pad/2, D, 0};   // load pad, left end
Point(13) = {-L/2, D, 0};

Line(1) = {1, 2};    // bottom
Line(2) = {2, 3};    // bottom
Line(3) = {3, 4};    // notch, left face
Line(4) = {4, 5};    // notch, V left
Line(5) = {5, 6};    // notch, V right
Line(6) = {6, 7};    // notch, right face
Line(7) = {7, 8};    // bottom
Line(8) = {8, 9};    // bottom
Line(9) = {9, 10};   // right
Line(10) = {10, 11}; // top
Line(11) = {11, 12}; // top, load pad
Line(12) = {12, 13}; // top
Line(13) = {13, 1};  // left
Curve Loop(1) = {1:13};
Plane Surface(1) = {1};

// mesh size: h_fine in the band |x| < band, growing linearly to h over `transition` mm
Field[1] = Box;
Field[1].VIn = h_fine;
Field[1].VOut = h;
Field[1].XMin = -band;
Field[1].XMax = band;
Field[1].YMin = -1;
Field[1].YMax = D + 1;
Field[1].Thickness = transition;
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.Algorithm = 6;  // frontal-Delaunay; a scene's geometry.algorithm overrides it

Physical Surface("domain") = {1};
Physical Curve("notch") = {3, 4, 5, 6};
Physical Curve("bottom") = {1, 2, 7, 8};
Physical Curve("right") = {9};
Physical Curve("top") = {10, 11, 12};
Physical Curve("load") = {11};
Physical Curve("left") = {13};
Physical Point("support_pin") = {2};
Physical Point("support_roller") = {8};
Physical Point("tip") = {5};
