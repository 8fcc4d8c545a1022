// The slope of slope_planar_joint.geo with its joint drawn ONCE: the rock below and the
// block above share the joint curve, so gmsh meshes them conforming, and the mesh is cut
// along the joint before it is distributed (the joint's group named by a
// [plasticity.joints.NAME] table is split automatically: docs/plasticity.md, "Joints in
// the strength reduction", automatic splitting). Height H, face dipping alpha degrees,
// toe at the origin on the fixed base y = 0, level crest y = H reaching L beyond the
// joint's exit; the joint dips psi from the face at height yd to the crest, nj segments
// of about h (transfinite, as in the hand-split file).
// Groups: "base" (fixed), "back" (rollers), "face", "crest" (free), "joint",
// cells "rock" (below) and "block" (above). 6-node triangles.
DefineConstant[
  H = {10.0, Name "Parameters/H"},
  alpha = {60.0, Name "Parameters/alpha"},
  psi = {30.0, Name "Parameters/psi"},
  yd = {2.0, Name "Parameters/yd"},
  L = {10.0, Name "Parameters/L"},
  h = {1.0, Name "Parameters/h"},
  algorithm = {6, Name "Parameters/algorithm"}
];
x1 = yd / Tan(alpha * Pi / 180);
x2 = H / Tan(alpha * Pi / 180);
x3 = x1 + (H - yd) / Tan(psi * Pi / 180);
xb = x3 + L;
nj = Ceil((H - yd) / Sin(psi * Pi / 180) / h - 1e-6);
Point(1) = {0, 0, 0, h};
Point(2) = {xb, 0, 0, h};
Point(3) = {xb, H, 0, h};
Point(4) = {x3, H, 0, h};
Point(5) = {x1, yd, 0, h};
Point(6) = {x2, H, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 1};
Line(6) = {5, 6};
Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Curve Loop(2) = {6, 7, 4};
Plane Surface(2) = {2};
Transfinite Curve {4} = nj + 1;
Physical Curve("base") = {1};
Physical Curve("back") = {2};
Physical Curve("crest") = {3, 7};
Physical Curve("face") = {5, 6};
Physical Curve("joint") = {4};
Physical Surface("rock") = {1};
Physical Surface("block") = {2};
Mesh.Algorithm = algorithm;
Mesh.ElementOrder = 2;
