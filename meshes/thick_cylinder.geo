// Quarter of a thick-walled cylinder a <= r <= b (Lamé; Timoshenko & Goodier, §28) in the
// plane x >= 0, y >= 0, unstructured triangles of size h. The symmetry cuts are the
// groups "x-symmetry" (the line x = 0: hold u_x) and "y-symmetry" (the line y = 0: hold
// u_y). The arcs are meshed by straight edges: with P2 the error converges with h.
// Parameters come from a scene's [geometry.parameters].
DefineConstant[
  a = {1, Name "Parameters/a"},
  b = {2, Name "Parameters/b"},
  h = {0.2, Name "Parameters/h"}
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

Physical Surface("domain") = {1};
Physical Curve("inner") = {4};
Physical Curve("outer") = {2};
Physical Curve("x-symmetry") = {3};
Physical Curve("y-symmetry") = {1};
