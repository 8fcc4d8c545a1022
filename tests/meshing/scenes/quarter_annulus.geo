// Quarter annulus 1 <= r <= 2, 0 <= θ <= π/2 with curved (second-order) cells by default:
// the arcs are circles, so gmsh places the mid-edge nodes of Mesh.ElementOrder = 2 on them.
// tests/meshing/test_curved.py meshes it with order 1, 2 and 3.
DefineConstant[
  h = {0.5, Name "Parameters/h"},
  order = {2, Name "Parameters/order"}
];
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {2, 0, 0};
Point(4) = {0, 2, 0};
Point(5) = {0, 1, 0};
Line(1) = {2, 3};        // y = 0
Circle(2) = {3, 1, 4};   // r = 2
Line(3) = {4, 5};        // x = 0
Circle(4) = {5, 1, 2};   // r = 1
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Surface("domain") = {1};
Physical Curve("boundary") = {1, 2, 3, 4};
Physical Curve("bottom") = {1};
Physical Curve("left") = {3};
Physical Point("corner") = {3};
Mesh.MeshSizeMax = h;
Mesh.ElementOrder = order;
