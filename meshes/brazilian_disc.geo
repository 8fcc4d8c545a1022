// Brazilian disc: a disc of diameter D = 50 mm centred at the origin, loaded by a uniform
// radial pressure on two strips of angular width 2 alpha (default 2 alpha = 10 degrees)
// centred on the top (0, R) and the bottom (0, -R): physical curves "strip_top" and
// "strip_bottom"; the rest of the rim is "rim". The loaded diameter is the y axis.
// Points for the supports that remove the rigid-body motions without touching the loaded
// diameter's interior: "top_centre" (0, R) and "bottom_centre" (0, -R), the strips'
// centres, where the exact u_x is 0 by symmetry (fixing u_x there stops the x
// translation and the rotation); "right_end" (R, 0) and "left_end" (-R, 0), the ends of
// the horizontal diameter, where the exact u_y is 0 (fixing u_y stops the y translation).
// All four conditions hold in the exact field, so they carry no force and keep it
// symmetric. Uniform element size h (default 1 mm: about 2,600 nodes); the strip ends are
// mesh nodes. gmsh also keeps a node at the centre (the arcs' centre point), which no
// element uses. Units: mm, degrees. Parameters come from a scene's [geometry.parameters].
// strip_deg is 2 alpha, the strips' angular width in degrees.
DefineConstant[
  D = {50, Name "Parameters/D"},
  strip_deg = {10, Name "Parameters/strip_deg"},
  h = {1, Name "Parameters/h"}
];

R = D/2;
al = strip_deg/2*Pi/180;

Point(1) = {0, 0, 0, h};                                  // centre (not meshed)
Point(2) = {R, 0, 0, h};                                  // right_end
Point(3) = {R*Sin(al), R*Cos(al), 0, h};                  // strip_top, right end
Point(4) = {0, R, 0, h};                                  // top_centre
Point(5) = {-R*Sin(al), R*Cos(al), 0, h};                 // strip_top, left end
Point(6) = {-R, 0, 0, h};                                 // left_end
Point(7) = {-R*Sin(al), -R*Cos(al), 0, h};                // strip_bottom, left end
Point(8) = {0, -R, 0, h};                                 // bottom_centre
Point(9) = {R*Sin(al), -R*Cos(al), 0, h};                 // strip_bottom, right end

Circle(1) = {2, 1, 3};  // rim
Circle(2) = {3, 1, 4};  // strip_top
Circle(3) = {4, 1, 5};  // strip_top
Circle(4) = {5, 1, 6};  // rim
Circle(5) = {6, 1, 7};  // rim
Circle(6) = {7, 1, 8};  // strip_bottom
Circle(7) = {8, 1, 9};  // strip_bottom
Circle(8) = {9, 1, 2};  // rim
Curve Loop(1) = {1:8};
Plane Surface(1) = {1};
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;  // frontal-Delaunay; a scene's geometry.algorithm overrides it

Physical Surface("domain") = {1};
Physical Curve("strip_top") = {2, 3};
Physical Curve("strip_bottom") = {6, 7};
Physical Curve("rim") = {1, 4, 5, 8};
Physical Point("top_centre") = {4};
Physical Point("bottom_centre") = {8};
Physical Point("right_end") = {2};
Physical Point("left_end") = {6};
