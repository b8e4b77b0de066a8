function varargout = e_rms(varargin)
%E_RMS RMS tracking error, (D2) of Gu & Zhu (2014), in percent of the desired range.
%   E = hystcomp.e_rms(YD, Y) is sqrt(mean((Y - YD).^2)) / (max YD - min YD) * 100.
%
%   See also hystcomp.e_m, hystcomp.e_mhe.
[varargout{1:max(nargout, 1)}] = hystcomp_mex('e_rms', varargin{:});
end
