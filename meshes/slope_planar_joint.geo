// A rock slope cut by one through-going joint that daylights on the face (planar sliding,
// Hoek and Bray, Rock Slope Engineering; Wyllie and Mah (2004)): height H, face dipping
// alpha degrees, toe at the origin on the fixed base y = 0, the level crest y = H reaching
// L beyond the joint's exit. The joint dips psi < alpha from the face at height yd up to
// the crest, so the block above it (a triangle) is free but for the joint.
// The joint is split in the geometry: the rock below and the block above are separate
// surfaces, and the joint is drawn twice (curve "joint" on both faces, the same points
// twice, AutoCoherence off so gmsh keeps them apart), meshed alike (transfinite, nj
// segments of about h). docs/plasticity.md, "Joints in the strength reduction".
// Groups: "base" (fixed), "back" (rollers), "face", "crest" (free), "joint" (both faces),
// cells "rock" (below) and "block" (above). 6-node triangles, gmsh 2D algorithm from the
// parameter (a scene's geometry.algorithm overrides it).
DefineConstant[
  H = {10.0, Name "Parameters/H"},
  alpha = {60.0, Name "Parameters/alpha"},
  psi = {30.0, Name "Parameters/psi"},
  yd = {2.0, Name "Parameters/yd"},
  L = {10.0, Name "Parameters/L"},
  h = {1.0, Name "Parameters/h"},
  algorithm = {6, Name "Parameters/algorithm"}
];
Geometry.AutoCoherence = 0;
x1 = yd / Tan(alpha * Pi / 180);
x2 = H / Tan(alpha * Pi / 180);
x3 = x1 + (H - yd) / Tan(psi * Pi / 180);
xb = x3 + L;
nj = Ceil((H - yd) / Sin(psi * Pi / 180) / h - 1e-6);
// the rock below the joint
Point(1) = {0, 0, 0, h};
Point(2) = {xb, 0, 0, h};
Point(3) = {xb, H, 0, h};
Point(4) = {x3, H, 0, h};
Point(5) = {x1, yd, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
// the block above it: its own copies of the joint's end points and of the joint
Point(6) = {x1, yd, 0, h};
Point(7) = {x2, H, 0, h};
Point(8) = {x3, H, 0, h};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 6};
Curve Loop(2) = {6, 7, 8};
Plane Surface(2) = {2};
Transfinite Curve {4, 8} = nj + 1;
Physical Curve("base") = {1};
Physical Curve("back") = {2};
Physical Curve("crest") = {3, 7};
Physical Curve("face") = {5, 6};
Physical Curve("joint") = {4, 8};
Physical Surface("rock") = {1};
Physical Surface("block") = {2};
Mesh.Algorithm = algorithm;
Mesh.ElementOrder = 2;
