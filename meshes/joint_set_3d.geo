// A prism W x W x H, H = n s (|x|, |y| <= W/2, 0 <= z <= H), cut by n horizontal
// through-going joints at z = s/2, 3s/2, ..., (n - 1/2) s (one joint set of spacing s, a
// joint per length s of the prism, the ends halfway between joints): the compliance
// of a persistent joint set, 1/E_eff = 1/E + 1/(k_n s) under a uniaxial stress normal to
// the joints (Goodman, Methods of Geological Engineering, 1976; Priest, Discontinuity
// Analysis for Rock Engineering, 1993). The prism is also cut by the planes x = 0 and
// y = 0 (conforming internal faces, not joints) so that the axis's points are mesh nodes:
// "pin_xy", "pin_y" on the bottom and "top_xy", "top_y" on the top (at x = 0 and x = W/2 on
// y = 0) hold each end block's rigid motions without restraining the uniform Poisson
// expansion about the axis. Groups: "rock" (volume), "bottom", "top", "joints" (surfaces;
// cut when meshed: [plasticity.joints]) and the four pins (points). OpenCASCADE kernel;
// uniform size h (first-order tetrahedra).
// gmsh's 3D algorithm is the parameter algorithm3d (1 Delaunay, 4 Frontal, 10 HXT).
SetFactory("OpenCASCADE");
DefineConstant[
  W = {1, Name "Parameters/W"},
  n = {3, Name "Parameters/n"},
  s = {0.25, Name "Parameters/s"},
  h = {0.2, Name "Parameters/h"},
  algorithm3d = {1, Name "Parameters/algorithm3d"}
];
If (n < 1 || n != Round(n))
  Error("joint_set_3d.geo: n = %g must be a whole number >= 1", n);
EndIf
H = n * s;
Box(1) = {-W/2, -W/2, 0, W, W, H};
cut() = {};
For k In {1 : n}
  r = newreg;
  Rectangle(r) = {-W, -W, (k - 0.5) * s, 2 * W, 2 * W};
  cut() += BooleanIntersection{ Surface{r}; Delete; }{ Volume{1}; };
EndFor
r = newreg; Rectangle(r) = {-H, -H, 0, 2 * H, 2 * H};
Rotate {{0, 1, 0}, {0, 0, 0}, Pi / 2} { Surface{r}; }
Translate {0, 0, H / 2} { Surface{r}; }
cut() += BooleanIntersection{ Surface{r}; Delete; }{ Volume{1}; };
r = newreg; Rectangle(r) = {-H, -H, 0, 2 * H, 2 * H};
Rotate {{1, 0, 0}, {0, 0, 0}, Pi / 2} { Surface{r}; }
Translate {0, 0, H / 2} { Surface{r}; }
cut() += BooleanIntersection{ Surface{r}; Delete; }{ Volume{1}; };
BooleanFragments{ Volume{1}; Delete; }{ Surface{cut()}; Delete; }
e = 1e-6 * H;
Physical Volume("rock") = Volume{:};
Physical Surface("bottom") = Surface In BoundingBox{-W, -W, -e, W, W, e};
Physical Surface("top") = Surface In BoundingBox{-W, -W, H - e, W, W, H + e};
joints() = {};
For k In {1 : n}
  joints() += Surface In BoundingBox{-W, -W, (k - 0.5) * s - e, W, W, (k - 0.5) * s + e};
EndFor
Physical Surface("joints") = joints();
Physical Point("pin_xy") = Point In BoundingBox{-e, -e, -e, e, e, e};
Physical Point("pin_y") = Point In BoundingBox{W/2 - e, -e, -e, W/2 + e, e, e};
Physical Point("top_xy") = Point In BoundingBox{-e, -e, H - e, e, e, H + e};
Physical Point("top_y") = Point In BoundingBox{W/2 - e, -e, H - e, W/2 + e, e, H + e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 4;
Mesh.Algorithm3D = algorithm3d;  // 1 Delaunay, 4 Frontal, 10 HXT
