// Specimen with one through-going joint for Jaeger's single plane of weakness (Jaeger,
// Cook and Zimmerman, Fundamentals of Rock Mechanics, 4th ed., 2007, section 4.7): a
// rectangle W x H (0 <= x <= W, 0 <= y <= H) crossed completely by a straight joint through
// its centre (W/2, H/2) that makes the angle beta (degrees, 0 <= beta < 90) with the x axis,
// so that its normal makes beta with the loading axis y. The joint is clipped to the
// rectangle: it ends on the left and right sides when W tan(beta) <= H, otherwise on the
// bottom and top; the sides it ends on are split there, so its end points are mesh nodes of
// the boundary. The two pieces are separate surfaces that share the joint line: element
// edges follow it and its nodes are shared (precrack the group "joint" to open it).
// Uniform mesh size h; the defaults give about 1,100 triangles.
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  W = {40, Name "Parameters/W"},
  H = {80, Name "Parameters/H"},
  beta = {45, Name "Parameters/beta"},
  h = {2.5, Name "Parameters/h"}
];

If (beta < 0 || beta >= 90)
  Error("jaeger_joint.geo: beta = %g must be in [0, 90) degrees", beta);
EndIf

t = Tan(beta * Pi / 180);
If (Fabs(W * t - H) < 1e-6 * H)
  Error("jaeger_joint.geo: the joint (beta = %g) runs through the corners; change beta, W or H", beta);
EndIf

Point(1) = {0, 0, 0, h};  // bottom_left (the x pin)
Point(2) = {W, 0, 0, h};
Point(3) = {W, H, 0, h};
Point(4) = {0, H, 0, h};

If (W * t <= H)
  // the joint ends on the left side (point 5) and on the right side (point 6)
  Point(5) = {0, 0.5 * H - 0.5 * W * t, 0, h};
  Point(6) = {W, 0.5 * H + 0.5 * W * t, 0, h};
  Line(1) = {1, 2};  // bottom
  Line(2) = {2, 6};  // right, below the joint
  Line(3) = {6, 3};  // right, above
  Line(4) = {3, 4};  // top
  Line(5) = {4, 5};  // left, above
  Line(6) = {5, 1};  // left, below
  Line(7) = {5, 6};  // joint
  Curve Loop(1) = {1, 2, -7, 6};
  Curve Loop(2) = {7, 3, 4, 5};
  Physical Curve("bottom") = {1};
  Physical Curve("right") = {2, 3};
  Physical Curve("top") = {4};
  Physical Curve("left") = {5, 6};
Else
  // the joint ends on the bottom (point 5) and on the top (point 6)
  Point(5) = {0.5 * W - 0.5 * H / t, 0, 0, h};
  Point(6) = {0.5 * W + 0.5 * H / t, H, 0, h};
  Line(1) = {1, 5};  // bottom, left of the joint
  Line(2) = {5, 2};  // bottom, right
  Line(3) = {2, 3};  // right
  Line(4) = {3, 6};  // top, right
  Line(5) = {6, 4};  // top, left
  Line(6) = {4, 1};  // left
  Line(7) = {5, 6};  // joint
  Curve Loop(1) = {2, 3, 4, -7};
  Curve Loop(2) = {1, 7, 5, 6};
  Physical Curve("bottom") = {1, 2};
  Physical Curve("right") = {3};
  Physical Curve("top") = {4, 5};
  Physical Curve("left") = {6};
EndIf

Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("domain") = {1, 2};
Physical Curve("joint") = {7};
Physical Point("bottom_left") = {1};
