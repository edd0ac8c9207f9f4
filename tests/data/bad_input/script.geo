SystemCall "touch cdem_pwned_by_geo";
Point(1) = {0, 0, 0, 1};
