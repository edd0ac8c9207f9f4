SystemCall "touch /tmp/cdem_pwned";
Merge "x.msh";
