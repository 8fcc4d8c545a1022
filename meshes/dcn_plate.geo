// Double centre notch plate after Zhu and Tang (Edo (2016), §2.4.5): a square
// plate 150 x 150 mm (0 <= x, y <= 150) with two zero-width notches of length c, inclined
// at alpha degrees to the x axis (counter-clockwise), centred at (75 - s/2, 75) and
// (75 + s/2, 75). The notches are embedded lines (element edges follow them; nodes on them
// are shared). Uniform mesh size h; the default gives 17,712 nodes and 34,938 triangles
// (Edo (2016): 17,551 nodes, 34,560 elements).
// Units: mm. Parameters come from a scene's [geometry.parameters].
DefineConstant[
  c = {30, Name "Parameters/c"},
  alpha = {45, Name "Parameters/alpha"},
  s = {50, Name "Parameters/s"},
  h = {1.24, Name "Parameters/h"}
];

A = 150;
dx = 0.5 * c * Cos(alpha * Pi / 180);
dy = 0.5 * c * Sin(alpha * Pi / 180);
x1 = 0.5 * A - 0.5 * s;  // notch 1 centre (x1, A/2)
x2 = 0.5 * A + 0.5 * s;  // notch 2 centre (x2, A/2)

Point(1) = {0, 0, 0, h};
Point(2) = {A, 0, 0, h};
Point(3) = {A, A, 0, h};
Point(4) = {0, A, 0, h};
Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // right
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // left
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Point(5) = {x1 - dx, 0.5 * A - dy, 0, h};
Point(6) = {x1 + dx, 0.5 * A + dy, 0, h};
Point(7) = {x2 - dx, 0.5 * A - dy, 0, h};
Point(8) = {x2 + dx, 0.5 * A + dy, 0, h};
Line(5) = {5, 6};  // notch 1
Line(6) = {7, 8};  // notch 2
Curve{5, 6} In Surface{1};

Physical Surface("domain") = {1};
Physical Curve("notch1") = {5};
Physical Curve("notch2") = {6};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Point("bottom_left") = {1};
