// A prism W x W x H (|x|, |y| <= W/2, |z| <= H/2) crossed completely by one planar joint
// through its centre whose normal makes the angle beta (degrees) with the z axis, in the
// xz plane: n = (sin beta, 0, cos beta). Jaeger's single plane of weakness in 3D (Jaeger,
// Cook and Zimmerman, Fundamentals of Rock Mechanics, 4th ed., 2007, section 4.7; the 2D
// scene's meshes/jaeger_joint.geo). The prism is also cut by the planes x = 0 and y = 0
// (conforming internal faces, not joints) so that the axis's points on the bottom are mesh
// nodes: "pin_xy" (0, 0, -H/2) and "pin_y" (W/2, 0, -H/2) hold the rigid motions without
// restraining the uniform Poisson expansion about the axis. Groups: "rock" (volume),
// "bottom", "top", "sides" (the four lateral faces), "joint" (surfaces; the joint is cut
// when meshed: [plasticity.joints]),
// "pin_xy", "pin_y" (points). The joint must end on the sides: W/2 tan(beta) < H/2.
// OpenCASCADE kernel; uniform size h (first-order tetrahedra).
// gmsh's 3D algorithm is the parameter algorithm3d (1 Delaunay, 4 Frontal, 10 HXT).
SetFactory("OpenCASCADE");
DefineConstant[
  W = {1, Name "Parameters/W"},
  H = {2.5, Name "Parameters/H"},
  beta = {45, Name "Parameters/beta"},
  h = {0.25, Name "Parameters/h"},
  algorithm3d = {1, Name "Parameters/algorithm3d"}
];
If (beta < 0 || beta >= 90 || W * Tan(beta * Pi / 180) >= H)
  Error("jaeger_joint_3d.geo: beta = %g must be in [0, 90) with W tan(beta) < H", beta);
EndIf
Box(1) = {-W/2, -W/2, -H/2, W, W, H};
Rectangle(10) = {-2*H, -2*H, 0, 4*H, 4*H};
Rotate {{0, 1, 0}, {0, 0, 0}, beta * Pi / 180} { Surface{10}; }
Rectangle(11) = {-2*H, -2*H, 0, 4*H, 4*H};
Rotate {{0, 1, 0}, {0, 0, 0}, Pi / 2} { Surface{11}; }
Rectangle(12) = {-2*H, -2*H, 0, 4*H, 4*H};
Rotate {{1, 0, 0}, {0, 0, 0}, Pi / 2} { Surface{12}; }
j() = BooleanIntersection{ Surface{10}; Delete; }{ Volume{1}; };
a() = BooleanIntersection{ Surface{11}; Delete; }{ Volume{1}; };
b() = BooleanIntersection{ Surface{12}; Delete; }{ Volume{1}; };
BooleanFragments{ Volume{1}; Delete; }{ Surface{j(), a(), b()}; Delete; }
e = 1e-6 * H;
outer() = CombinedBoundary{ Volume{:}; };
Physical Volume("rock") = Volume{:};
bottom() = Surface In BoundingBox{-W, -W, -H/2 - e, W, W, -H/2 + e};
top() = Surface In BoundingBox{-W, -W, H/2 - e, W, W, H/2 + e};
sides() = outer();
sides() -= bottom();
sides() -= top();
Physical Surface("bottom") = bottom();
Physical Surface("top") = top();
Physical Surface("sides") = sides();
c = Cos(beta * Pi / 180);
s = Sin(beta * Pi / 180);
inner() = Surface In BoundingBox{-W, -W, -H, W, W, H};
inner() -= outer();
joint() = {};
For k In {0 : #inner() - 1}
  bb() = BoundingBox Surface{inner(k)};
  xm = (bb(0) + bb(3)) / 2; zm = (bb(2) + bb(5)) / 2;
  If (Fabs(s * xm + c * zm) < 1e-6 * H && bb(3) - bb(0) > 1e-6 * H && bb(4) - bb(1) > 1e-6 * H)
    joint() += inner(k);
  EndIf
EndFor
Physical Surface("joint") = joint();
Physical Point("pin_xy") = Point In BoundingBox{-e, -e, -H/2 - e, e, e, -H/2 + e};
Physical Point("pin_y") = Point In BoundingBox{W/2 - e, -e, -H/2 - e, W/2 + e, e, -H/2 + e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 4;
Mesh.Algorithm3D = algorithm3d;  // 1 Delaunay, 4 Frontal, 10 HXT
