% Runs MAAST for ARAIM 2 (stanford-gps-lab/maast_for_araim_2) on the
% MAAST scenario of issue 36 (docs/runs/availability_maast_g24e24_ed259a.toml),
% without its GUI or plots, and writes every user-epoch's outputs as CSV.
% Called by scripts/maast2/run.sh from a patched copy of the reference
% (scripts/maast2/README.md); the reference is not part of this repository.
%
% Settings: those of MAAST for ARAIM 2's main_maast_araim.m (its
% "Vertical-ARAIM settings (example)" block, not the H-ARAIM `if 1` block),
% with the issue's ISM and LPV-200 limits, and with
%   config "matched": the allocations of raim-core's AraimConfig::default
%     (SPEC 9.1: P_THRES 8e-8, P_FA_HOR 9e-8) and one independent sample per
%     epoch (N_es = 1, exposure 0, no P_md cap), i.e. the ADD v3.0 per-epoch
%     form our engine computes;
%   config "shipped": MAAST 2's own V-ARAIM example allocations (ADD v4.2
%     with N_es 25, exposure 1/24 h, P_md cap, P_THRES 6e-8, P_FA_HOR 9e-7).
% Environment: MAAST2_CONFIG (matched|shipped), MAAST2_FDE (0|1),
% MAAST2_T0, MAAST2_T1, MAAST2_STEP (s, GPS seconds of the almanacs' week),
% MAAST2_OUT (CSV path); optional MAAST2_FAST (0|1, default 1 as committed).

% norminv / normcdf: scripts/maast2/octave (Matlab Statistics Toolbox forms)

global ARAIM_USRMASK_GPS ARAIM_USRMASK_GLO ARAIM_USRMASK_GAL ARAIM_USRMASK_BDU
global ARAIM_SIN_USRMASK_GPS ARAIM_SIN_USRMASK_GLO ARAIM_SIN_USRMASK_GAL
global ARAIM_SIN_USRMASK_BDU
global MAAST2_OUT COL_USR_LL

config = getenv('MAAST2_CONFIG');
fde = str2double(getenv('MAAST2_FDE'));
TStart = str2double(getenv('MAAST2_T0'));
TEnd = str2double(getenv('MAAST2_T1'));
TStep = str2double(getenv('MAAST2_STEP'));
csv_out = getenv('MAAST2_OUT');
MAAST2_OUT = [csv_out '.octave'];

% 5 deg mask on every constellation (issue 36).
ARAIM_USRMASK_GPS = 5; ARAIM_USRMASK_GLO = 5; ARAIM_USRMASK_GAL = 5; ARAIM_USRMASK_BDU = 5;
ARAIM_SIN_USRMASK_GPS = sin(ARAIM_USRMASK_GPS*pi/180);
ARAIM_SIN_USRMASK_GLO = sin(ARAIM_USRMASK_GLO*pi/180);
ARAIM_SIN_USRMASK_GAL = sin(ARAIM_USRMASK_GAL*pi/180);
ARAIM_SIN_USRMASK_BDU = sin(ARAIM_USRMASK_BDU*pi/180);

% ISM of issue 36: sigma_URA 1 m, sigma_URE 2/3 m, b_nom 0.75 m, P_sat 1e-5,
% P_const 1e-8 (GPS) and 1e-4 (Galileo). MAAST 2 takes a rate and a mean
% fault duration: P = rate * MFD, so rate = P and MFD = 1 h.
isd.ura_gps = 1; isd.ura_gal = 1; isd.ura_glo = 9; isd.ura_bdu = Inf;
isd.bias_gps = 0.75; isd.bias_gal = 0.75; isd.bias_glo = 0; isd.bias_bdu = 0;
isd.ure_gps = 2/3; isd.ure_gal = 2/3; isd.ure_glo = 8; isd.ure_bdu = Inf;
% b_cont 0: the ADD v3.0 thresholds and sigma_acc carry no bias (raim-core).
isd.bias_cont_gps = 0; isd.bias_cont_gal = 0; isd.bias_cont_glo = 0; isd.bias_cont_bdu = 0;
isd.rsat_gps = 1e-5; isd.rsat_gal = 1e-5; isd.rsat_glo = 3.4e-5; isd.rsat_bdu = 1e-5;
isd.mfd_sat_gps = 1; isd.mfd_sat_gal = 1; isd.mfd_sat_glo = 3; isd.mfd_sat_bdu = 1;
isd.rconst_gps = 1e-8; isd.rconst_gal = 1e-4; isd.rconst_glo = 1e-5; isd.rconst_bdu = 1e-4;
isd.mfd_const_gps = 1; isd.mfd_const_gal = 1; isd.mfd_const_glo = 10; isd.mfd_const_bdu = 1;

% MAAST 2's Vertical-ARAIM settings (example), as committed.
prm.fde_flag = fde;
prm.fde_wf_flag = 0;
prm.pl0_fde = 0;
prm.phmi_vert = 9.8e-8;
prm.phmi_hor = 2e-9;
prm.p_thres = 6e-8;
prm.p_exc_thres = 1;
prm.pfa_vert = 3.9e-6;
prm.pfa_hor = 0.9e-6;
prm.p_emt = 1e-5;
prm.pl_tol = 1e-2;
prm.fc_thres = .01;
prm.sig_acc_max_vert = 1.86;
prm.sig_acc_max_hor1 = 3;
prm.sig_acc_max_hor2 = 3;
prm.N_es_int = 25;
prm.N_es_cont = 25;
prm.t_exp = 1/24;
prm.vpl_target = 35;
prm.hpl_target = 40;
prm.emt_target = 15;
prm.sig_acc_target = 1.87;
prm.hpl_variant = 0;
prm.max_pmd_flag = 1;
prm.opt = 1; % position optimisation on, as committed; run.sh records the outputs without it too
prm.fast = 1; % as committed: dual faults bounded by one term, fault modes consolidated
if ~isempty(getenv('MAAST2_FAST'))
  prm.fast = str2double(getenv('MAAST2_FAST')); % diagnostic: MAAST2_FAST=0 computes every mode exactly
end
if strcmp(config, 'matched')
  prm.p_thres = 8e-8;   % raim-core AraimConfig::default (SPEC 9.1)
  prm.pfa_hor = 9e-8;   % idem
  prm.N_es_int = 1;     % one independent sample per epoch: PHMI and P_FA per epoch
  prm.N_es_cont = 1;
  prm.t_exp = 0;        % P_fault over the exposure = P_fault at the instant (ADD v3.0)
  prm.max_pmd_flag = 0; % no cap of P_md by P_exp / P_inst / N_es (a v4.2 refinement)
elseif ~strcmp(config, 'shipped')
  error('MAAST2_CONFIG must be matched or shipped');
end

% The DO-229 GPS almanac and MAAST's 24-slot Galileo almanac: byte for
% byte ../shared/data/almanac_gps24_mops.yuma and almanac_galileo24.yuma.
svfile = {'almmops.txt', 'almanac Galileo 24 Week 703.alm.txt'};

init_const;
init_col_labels_araim;
init_mops;

dual_freq = 1;                % L1/L5, E1/E5a
usrcnmpfun = 'af_cnmp_259a';  % ED-259A as MAAST 2 has it
init_cnmp_mops;
usrpolyfile = 'usrworld.dat';
usrlatstep = 10;
usrlonstep = 10;
pa_mode = 1;
vhal = [35, 40, 15, 1.87];    % LPV-200
outputs = [1 1 0 0];
percent = 0.995;
latmax = pi/2;

cpu0 = cputime;
svmrun_araim(usrcnmpfun, usrpolyfile, svfile, TStart, TEnd, TStep, ...
             usrlatstep, usrlonstep, outputs, percent, vhal, pa_mode, ...
             dual_freq, latmax, prm, isd);
cpu_s = cputime - cpu0;

r = load(MAAST2_OUT);
[nusr, nt] = size(r.vpl);
fid = fopen(csv_out, 'w');
fprintf(fid, '# config=%s fast=%d fde=%d t0=%g t1=%g step=%g cpu_s=%.3f users=%d epochs=%d\n', ...
        config, prm.fast, fde, TStart, TEnd, TStep, cpu_s, nusr, nt);
fprintf(fid, 'lat_deg,lon_deg,t_s,vpl_m,hpl_m,emt_m,sig_acc_m,vpl_noopt_m,hpl_noopt_m,emt_noopt_m,sig_acc_noopt_m\n');
for k = 1:nt
  t = TStart + (k - 1) * TStep;
  for u = 1:nusr
    n = r.noopt_vhpl(u, :, k); % [vpl emt sig_acc hpl]
    fprintf(fid, '%g,%g,%g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n', ...
            r.usrdata(u, COL_USR_LL(1)), r.usrdata(u, COL_USR_LL(2)), t, ...
            r.vpl(u, k), r.hpl(u, k), r.emt(u, k), r.sig_acc(u, k), ...
            n(1), n(4), n(2), n(3));
  end
end
fclose(fid);
delete(MAAST2_OUT);
printf('maast2 done: config=%s fde=%d %d users x %d epochs, %.1f CPU s, %.1f user-epochs per CPU s\n', ...
       config, fde, nusr, nt, cpu_s, nusr * nt / cpu_s);
