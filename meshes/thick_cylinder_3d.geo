// Quarter of a thick-walled cylinder a <= r <= b, 0 <= z <= l (Lamé; Timoshenko &
// Goodier, §28): the quarter annulus of thick_cylinder.geo extruded along z in n layers
// of prisms split into tetrahedra. Groups: "inner" (r = a), "outer" (r = b),
// "x-symmetry" (x = 0: hold u_x), "y-symmetry" (y = 0: hold u_y), "ends" (z = 0 and
// z = l: hold u_z for the plane-strain state of a long cylinder).
// Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {1, Name "Parameters/a"},
  b = {2, Name "Parameters/b"},
  l = {0.5, Name "Parameters/l"},
  h = {0.25, Name "Parameters/h"},
  n = {2, Name "Parameters/n"}
];

Point(1) = {0, 0, 0, h};
Point(2) = {a, 0, 0, h};
Point(3) = {b, 0, 0, h};
Point(4) = {0, b, 0, h};
Point(5) = {0, a, 0, h};
Line(1) = {2, 3};        // y = 0
Circle(2) = {3, 1, 4};   // r = b
Line(3) = {4, 5};        // x = 0
Circle(4) = {5, 1, 2};   // r = a
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Mesh.MeshSizeMax = h;
body[] = Extrude {0, 0, l} { Surface{1}; Layers{n}; };
// body[0]: top (z = l), body[1]: volume, body[2..5]: the sides extruded from curves 1..4

Physical Volume("domain") = {body[1]};
Physical Surface("inner") = {body[5]};
Physical Surface("outer") = {body[3]};
Physical Surface("x-symmetry") = {body[4]};
Physical Surface("y-symmetry") = {body[2]};
Physical Surface("ends") = {1, body[0]};
