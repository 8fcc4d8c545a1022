// Box [0, lx] x [0, ly] x [0, lz] meshed with n x n x n hexahedral layers, each split into
// six tetrahedra by extrusion (no recombination): a structured tetrahedral mesh for the
// manufactured-solution study (geofrac bench mms3d). Parameters come from a scene's
// [geometry.parameters].
DefineConstant[
  lx = {1, Name "Parameters/lx"},
  ly = {1, Name "Parameters/ly"},
  lz = {1, Name "Parameters/lz"},
  n = {4, Name "Parameters/n"}
];

Point(1) = {0, 0, 0};
line[] = Extrude {lx, 0, 0} { Point{1}; Layers{n}; };
face[] = Extrude {0, ly, 0} { Curve{line[1]}; Layers{n}; };
body[] = Extrude {0, 0, lz} { Surface{face[1]}; Layers{n}; };

Physical Volume("domain") = {body[1]};
Physical Surface("boundary") = {face[1], body[0], body[2], body[3], body[4], body[5]};
Physical Surface("bottom") = {face[1]};
Physical Surface("top") = {body[0]};
