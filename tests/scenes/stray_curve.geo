Point(1) = {0, 0, 0, 0.5}; Point(2) = {2, 0, 0, 0.5}; Point(3) = {2, 1, 0, 0.5}; Point(4) = {0, 1, 0, 0.5};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Point(5) = {3, 0, 0, 0.5}; Point(6) = {3, 1, 0, 0.5}; Line(5) = {5, 6};
Physical Surface("domain") = {1};
Physical Curve("fixed") = {4};
Physical Curve("stray") = {5};
