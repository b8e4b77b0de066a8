function v = version()
%VERSION The version of the hystcomp library the MEX gateway was built with, e.g. '0.1.0'.
v = hystcomp_mex('version');
end
