// encoder_regs: register file of the encoder core, the window bank and its snapshot.
//
// Bus: a request (reg_rd_i or reg_wr_i, one cycle, with reg_addr_i/reg_wdata_i) is answered
// three cycles after it is presented (the "pipelined bus" section below) by reg_ack_o with
// reg_rdata_o; reg_err_o comes with the ack when the address is unknown, the register is
// read-only, the value is refused, or rd and wr are both high. One request a cycle is allowed.
// A refused write changes nothing but STATUS.BAD_WRITE. Addresses, fields and their widths come from
// the generated omniloc_regs.vh (single source of truth: common/regmap.json); the CLK_HZ/TICK_HZ
// defaults are the paper's 40 MHz and 100 Hz.
//
// Window bank: at capture_i (tick while enabled) the sequence number increments and the capture
// timestamp and STATUS are recorded; the channels' window registers update in the same edge.
// win_valid_o pulses in the cycle after, when all of it is visible. Reading SNAP_SEQ, or
// win_consumed_i (the link streaming the window), copies the whole bank (seq, timestamp, status,
// dir, counts, positions) into the one frozen bank that SNAP_* read and that the link sends byte
// by byte (bank_idx_i -> bank_byte_o, the WINDOW body layout), so the reads that follow belong to
// the same window even if captures happen meanwhile. The gyro's window (gyro_*_i, from gyro_accum
// ticked by the window tick, so latched at the same edge as a capture) is part of the bank: copied
// with the counts, read as SNAP_GYRO_SUM and SNAP_GYRO. STATUS.GYRO_FAULT is set in the cycle after a capture whose gyro flags are not 0
// (so it shows in the next window's status byte; the window's own flags are in its body).
// STATUS.OVERRUN: a capture while the previous window was neither latched through SNAP_SEQ nor
// acknowledged by win_consumed_i. A flag set and cleared (W1C) in the same cycle stays set.
//
// Assumptions: capture_i and illegal_i are one-cycle pulses; rst_i synchronous, active high.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module encoder_regs #(
    parameter integer CLK_HZ = `OMNILOC_PAPER_CLOCK_HZ,
    parameter integer TICK_HZ = `OMNILOC_TICK_HZ,
    parameter integer CHANNELS = `OMNILOC_CHANNELS,   // CONFIG.CHANNELS: the channels encoder_core built
    parameter integer BANK_IDX_W = $clog2(`OMNILOC_BODY_WINDOW_BYTES + 1)
) (
    input  wire                                         clk_i,
    input  wire                                         rst_i,
    // register bus
    input  wire [`OMNILOC_ADDR_W-1:0]                   reg_addr_i,
    input  wire                                         reg_rd_i,
    input  wire                                         reg_wr_i,
    input  wire [`OMNILOC_DATA_W-1:0]                   reg_wdata_i,
    output wire [`OMNILOC_DATA_W-1:0]                   reg_rdata_o,
    output wire                                         reg_ack_o,
    output wire                                         reg_err_o,
    // control to the datapath
    output wire                                         enable_o,
    output wire [`OMNILOC_CONTROL_DECODE_W-1:0]         decode_o,
    output wire                                         stream_o,
    output wire [`OMNILOC_FILTER_LENGTH_W-1:0]          filter_len_o,
    output wire [`OMNILOC_PERIOD_CYCLES_W-1:0]          period_o,
    // events and live values from the datapath
    input  wire                                         capture_i,
    input  wire [`OMNILOC_STATUS_ILLEGAL_W-1:0]         illegal_i,
    input  wire                                         win_consumed_i,
    input  wire [`OMNILOC_DATA_W-1:0]                   timestamp_i,
    input  wire [`OMNILOC_CHANNELS*`OMNILOC_DATA_W-1:0] win_count_i,
    input  wire [`OMNILOC_CHANNELS*`OMNILOC_DATA_W-1:0] win_position_i,
    input  wire [`OMNILOC_SNAP_DIR_DIR_W-1:0]           win_dir_i,
    input  wire [`OMNILOC_CHANNELS*`OMNILOC_ERROR_COUNT_BITS-1:0] err_count_i,  // saturating
    // the gyro's window (gyro_accum), latched at the same capture edge as the counts
    input  wire signed [`OMNILOC_GYRO_SUM_BITS-1:0]     gyro_sum_i,
    input  wire [`OMNILOC_GYRO_COUNT_BITS-1:0]          gyro_count_i,
    input  wire [`OMNILOC_BODY_WINDOW_GYRO_FLAGS_W-1:0] gyro_flags_i,
    // window bank, valid from the cycle after the capture until the next one
    output wire                                         win_valid_o,
    output wire [`OMNILOC_DATA_W-1:0]                   win_seq_o,
    output wire [`OMNILOC_DATA_W-1:0]                   win_timestamp_o,
    output wire [`OMNILOC_BODY_WINDOW_STATUS_W-1:0]     win_status_o,
    output wire [`OMNILOC_BODY_WINDOW_STATUS_W-1:0]     status_o,
    // the frozen bank byte by byte in the WINDOW layout (TELEMETRY / SNAPSHOT_RESP body)
    input  wire [BANK_IDX_W-1:0]                        bank_idx_i,
    output wire [7:0]                                   bank_byte_o
);

localparam integer DATA_W = `OMNILOC_DATA_W;
localparam integer CH = `OMNILOC_CHANNELS;
// STATUS as a window carries it: the low byte (WINDOW.status of the frame layouts).
localparam integer BYTE_W = `OMNILOC_BODY_WINDOW_STATUS_W;
localparam integer ST_W = `OMNILOC_STATUS_BITS;
localparam [DATA_W-1:0] DEFAULT_PERIOD_CYCLES = CLK_HZ / TICK_HZ;
localparam [DATA_W-1:0] PERIOD_MIN_CYCLES = `OMNILOC_PERIOD_MIN_CYCLES;
localparam integer ILL_LSB = `OMNILOC_STATUS_ILLEGAL_LSB;
localparam integer ILL_W = `OMNILOC_STATUS_ILLEGAL_W;
localparam integer OVR_BIT = `OMNILOC_STATUS_OVERRUN_LSB;
localparam integer BAD_BIT = `OMNILOC_STATUS_BAD_WRITE_LSB;
localparam integer GYR_BIT = `OMNILOC_STATUS_GYRO_FAULT_LSB;
localparam integer GSUM_W = `OMNILOC_GYRO_SUM_BITS;
localparam integer GCNT_W = `OMNILOC_GYRO_COUNT_BITS;
localparam integer GFLG_W = `OMNILOC_BODY_WINDOW_GYRO_FLAGS_W;
localparam integer DEC_LSB = `OMNILOC_CONTROL_DECODE_LSB;
localparam integer DEC_W = `OMNILOC_CONTROL_DECODE_W;
localparam integer FLT_W = `OMNILOC_FILTER_LENGTH_W;
localparam integer DIR_W = `OMNILOC_SNAP_DIR_DIR_W;
localparam integer CFG_CH_W = `OMNILOC_CONFIG_CHANNELS_W;
localparam integer ERR_W = `OMNILOC_ERROR_COUNT_BITS;
localparam [CFG_CH_W-1:0] CHANNELS_FIELD = CHANNELS[CFG_CH_W-1:0];

// ---- control registers ----
reg              enable_q;
reg [DEC_W-1:0]  decode_q;
reg              stream_q;
reg [FLT_W-1:0]  filter_q;
reg [DATA_W-1:0] period_q;
reg [ST_W-1:0]   status_q;

assign enable_o = enable_q;
assign decode_o = decode_q;
assign stream_o = stream_q;
assign filter_len_o = filter_q;
assign period_o = period_q;
assign status_o = {{(BYTE_W - ST_W){1'b0}}, status_q};

// ---- window bank and snapshot ----
reg                 win_valid_q;
reg [DATA_W-1:0]    seq_q;
reg [DATA_W-1:0]    win_ts_q;
reg [BYTE_W-1:0]    win_status_q;
reg                 pending_q;

// The frozen bank: the WINDOW body (seq, timestamp, counts, dir, status at their offsets) and the
// positions. Pure data: no reset (it is 0 from configuration, and only read after a latch).
localparam integer BODY_BYTES = `OMNILOC_BODY_WINDOW_BYTES;
localparam integer W_SEQ = `OMNILOC_BODY_WINDOW_SEQ_LSB;
localparam integer W_TS = `OMNILOC_BODY_WINDOW_TIMESTAMP_CYCLES_LSB;
localparam integer W_COUNT = `OMNILOC_BODY_WINDOW_COUNT_LSB;
localparam integer W_DIR = `OMNILOC_BODY_WINDOW_DIR_LSB;
localparam integer W_STAT = `OMNILOC_BODY_WINDOW_STATUS_LSB;
localparam integer BDIR_W = `OMNILOC_BODY_WINDOW_DIR_W;
localparam integer W_GSUM = `OMNILOC_BODY_WINDOW_GYRO_SUM_LSB;
localparam integer W_GCNT = `OMNILOC_BODY_WINDOW_GYRO_COUNT_LSB;
localparam integer W_GFLG = `OMNILOC_BODY_WINDOW_GYRO_FLAGS_LSB;
localparam integer BGSUM_W = `OMNILOC_BODY_WINDOW_GYRO_SUM_W;
reg [8*BODY_BYTES-1:0] fz_body_q = {8*BODY_BYTES{1'b0}};
reg [CH*DATA_W-1:0]    fz_pos_q = {CH*DATA_W{1'b0}};
wire [DATA_W-1:0] snap_ts_q = fz_body_q[W_TS +: DATA_W];
wire [CH*DATA_W-1:0] snap_count_q = fz_body_q[W_COUNT +: CH*DATA_W];
wire [DIR_W-1:0] snap_dir_q = fz_body_q[W_DIR +: DIR_W];
wire [BYTE_W-1:0] snap_status_q = fz_body_q[W_STAT +: BYTE_W];
wire [DATA_W-1:0] snap_gsum_q = fz_body_q[W_GSUM +: DATA_W];
wire [GCNT_W-1:0] snap_gcnt_q = fz_body_q[W_GCNT +: GCNT_W];
wire [GFLG_W-1:0] snap_gflg_q = fz_body_q[W_GFLG +: GFLG_W];
// The gyro sum as the body and SNAP_GYRO_SUM carry it: sign-extended to the body field.
wire [BGSUM_W-1:0] gyro_sum_ext = {{(BGSUM_W - GSUM_W){gyro_sum_i[GSUM_W-1]}}, gyro_sum_i};
wire [CH*DATA_W-1:0] snap_pos_q = fz_pos_q;
localparam [BANK_IDX_W-1:0] LAST_IDX = BODY_BYTES[BANK_IDX_W-1:0];
wire [8*BODY_BYTES+7:0] fz_ext = {8'd0, fz_body_q};
assign bank_byte_o = (bank_idx_i < LAST_IDX) ? fz_ext[8*bank_idx_i +: 8] : 8'd0;

assign win_valid_o = win_valid_q;
assign win_seq_o = seq_q;
assign win_timestamp_o = win_ts_q;
assign win_status_o = win_status_q;

// ---- pipelined bus ----
// Stage R (the request edge t): the request and its decoded address and value checks are
// registered (rq_*), computed only from the request's own wires. Stage E (edge t+1): the request
// takes effect exactly as an unpipelined register file would take it at that edge (writes, W1C,
// SNAP_SEQ latch, errors), and the read data is sampled: the first mux level (the four words of a
// group, by the low address bits) into grp_q. Stage O (edge t+2): the group is chosen and the
// answer registered: reg_ack_o / reg_err_o / reg_rdata_o are visible after edge t+2, i.e. three
// cycles after the request is presented. Back-to-back requests are allowed (one a cycle).
localparam integer MUX_LO = 2;                   // words per group: 2^MUX_LO
localparam integer MUX_HI = 3;                   // groups: 2^MUX_HI (32 words, addresses 0x00..0x1F)

wire req_rd = reg_rd_i && !reg_wr_i;
wire req_wr = reg_wr_i && !reg_rd_i;

// Value checks of the writable registers: no bit above the register's fields, DECODE one of its values.
wire [DEC_W-1:0] req_wdecode = reg_wdata_i[DEC_LSB +: DEC_W];
wire decode_ok = (req_wdecode == `OMNILOC_CONTROL_DECODE_X4) || (req_wdecode == `OMNILOC_CONTROL_DECODE_X2)
              || (req_wdecode == `OMNILOC_CONTROL_DECODE_X1);
wire control_ok = (reg_wdata_i[DATA_W-1:`OMNILOC_CONTROL_BITS] == {(DATA_W - `OMNILOC_CONTROL_BITS){1'b0}}) && decode_ok;
wire filter_ok = (reg_wdata_i[DATA_W-1:`OMNILOC_FILTER_BITS] == {(DATA_W - `OMNILOC_FILTER_BITS){1'b0}});
// period >= PERIOD_MIN_CYCLES, split so that no 32-bit carry chain is needed: any bit above the
// minimum's width set, or the low bits compared on their own.
localparam integer PMIN_W = $clog2(`OMNILOC_PERIOD_MIN_CYCLES + 1);
wire period_ok = (reg_wdata_i[DATA_W-1:PMIN_W] != {(DATA_W - PMIN_W){1'b0}})
              || (reg_wdata_i[PMIN_W-1:0] >= PERIOD_MIN_CYCLES[PMIN_W-1:0]);

reg addr_known;
reg addr_writable;
always @(*) begin
    addr_known = `OMNILOC_ADDR_KNOWN(reg_addr_i) && (reg_addr_i != `OMNILOC_REG_LINK_ERRORS)
              && (reg_addr_i != `OMNILOC_REG_GYRO_STATE);
    addr_writable = `OMNILOC_ADDR_WRITABLE(reg_addr_i);
end

// Stage R registers.
reg              rq_rd, rq_wr, rq_both;   // valid bits (reset)
reg              rq_known, rq_writable;
reg              rq_control, rq_filter, rq_period, rq_status, rq_snap_seq;
reg              rq_control_ok, rq_filter_ok, rq_period_ok;
reg [MUX_LO+MUX_HI-1:0] rq_word;
reg [DATA_W-1:0] rq_wdata;
always @(posedge clk_i) begin
    // Data: no reset (only used with the valid bits).
    rq_known      <= addr_known;
    rq_writable   <= addr_writable;
    rq_control    <= (reg_addr_i == `OMNILOC_REG_CONTROL);
    rq_filter     <= (reg_addr_i == `OMNILOC_REG_FILTER);
    rq_period     <= (reg_addr_i == `OMNILOC_REG_PERIOD);
    rq_status     <= (reg_addr_i == `OMNILOC_REG_STATUS);
    rq_snap_seq   <= (reg_addr_i == `OMNILOC_REG_SNAP_SEQ);
    rq_control_ok <= control_ok;
    rq_filter_ok  <= filter_ok;
    rq_period_ok  <= period_ok;
    rq_word       <= reg_addr_i[MUX_LO+MUX_HI-1:0];
    rq_wdata      <= reg_wdata_i;
end
always @(posedge clk_i) begin
    if (rst_i) begin
        rq_rd   <= 1'b0;
        rq_wr   <= 1'b0;
        rq_both <= 1'b0;
    end else begin
        rq_rd   <= req_rd;
        rq_wr   <= req_wr;
        rq_both <= reg_rd_i && reg_wr_i;
    end
end

wire [DEC_W-1:0] wdecode = rq_wdata[DEC_LSB +: DEC_W];
wire wr_control = rq_wr && rq_control && rq_control_ok;
wire wr_filter = rq_wr && rq_filter && rq_filter_ok;
wire wr_period = rq_wr && rq_period && rq_period_ok;
wire wr_status = rq_wr && rq_status;
wire refused = rq_wr && ((rq_control && !rq_control_ok) || (rq_filter && !rq_filter_ok)
                         || (rq_period && !rq_period_ok));

// The readable words by address (0 where nothing is), fields at their LSBs.
function [DATA_W-1:0] word;
    input [`OMNILOC_ADDR_W-1:0] i;
    begin
        word = {DATA_W{1'b0}};
        case (i)
            `OMNILOC_REG_ID: word = `OMNILOC_ID;
            `OMNILOC_REG_VERSION: word = `OMNILOC_VERSION;
            `OMNILOC_REG_CONTROL: begin
                word[`OMNILOC_CONTROL_ENABLE_LSB] = enable_q;
                word[DEC_LSB +: DEC_W] = decode_q;
                word[`OMNILOC_CONTROL_STREAM_LSB] = stream_q;
            end
            `OMNILOC_REG_FILTER: word[`OMNILOC_FILTER_LENGTH_LSB +: FLT_W] = filter_q;
            `OMNILOC_REG_PERIOD: word = period_q;
            `OMNILOC_REG_STATUS: word[ST_W-1:0] = status_q;
            `OMNILOC_REG_TIMESTAMP: word = timestamp_i;
            `OMNILOC_REG_SNAP_SEQ: word = seq_q;
            `OMNILOC_REG_SNAP_TIMESTAMP: word = snap_ts_q;
            `OMNILOC_REG_SNAP_DIR: word[`OMNILOC_SNAP_DIR_DIR_LSB +: DIR_W] = snap_dir_q;
            `OMNILOC_REG_SNAP_STATUS: word[BYTE_W-1:0] = snap_status_q;
            `OMNILOC_REG_SNAP_COUNT0: word = snap_count_q[0*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_COUNT1: word = snap_count_q[1*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_COUNT2: word = snap_count_q[2*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_COUNT3: word = snap_count_q[3*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_POSITION0: word = snap_pos_q[0*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_POSITION1: word = snap_pos_q[1*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_POSITION2: word = snap_pos_q[2*DATA_W +: DATA_W];
            `OMNILOC_REG_SNAP_POSITION3: word = snap_pos_q[3*DATA_W +: DATA_W];
            `OMNILOC_REG_ERROR_COUNT0: word[ERR_W-1:0] = err_count_i[0*ERR_W +: ERR_W];
            `OMNILOC_REG_ERROR_COUNT1: word[ERR_W-1:0] = err_count_i[1*ERR_W +: ERR_W];
            `OMNILOC_REG_ERROR_COUNT2: word[ERR_W-1:0] = err_count_i[2*ERR_W +: ERR_W];
            `OMNILOC_REG_ERROR_COUNT3: word[ERR_W-1:0] = err_count_i[3*ERR_W +: ERR_W];
            `OMNILOC_REG_SNAP_GYRO_SUM: word = snap_gsum_q;
            `OMNILOC_REG_SNAP_GYRO: begin
                word[`OMNILOC_SNAP_GYRO_COUNT_LSB +: GCNT_W] = snap_gcnt_q;
                word[`OMNILOC_SNAP_GYRO_FLAGS_LSB +: GFLG_W] = snap_gflg_q;
            end
            `OMNILOC_REG_CONFIG: word[`OMNILOC_CONFIG_CHANNELS_LSB +: CFG_CH_W] = CHANNELS_FIELD;
            default: word = {DATA_W{1'b0}};
        endcase
    end
endfunction

// Stage E: first mux level (word rq_word[MUX_LO-1:0] of every group).
reg [DATA_W-1:0] grp_d [0:(1<<MUX_HI)-1];
integer gi, wi;
reg [`OMNILOC_ADDR_W-1:0] widx;
always @(*) begin
    widx = {`OMNILOC_ADDR_W{1'b0}};
    for (gi = 0; gi < (1 << MUX_HI); gi = gi + 1) begin
        grp_d[gi] = {DATA_W{1'b0}};
        for (wi = 0; wi < (1 << MUX_LO); wi = wi + 1) begin
            widx = gi[`OMNILOC_ADDR_W-1:0] * (1 << MUX_LO) + wi[`OMNILOC_ADDR_W-1:0];
            if ({{(32-MUX_LO){1'b0}}, rq_word[MUX_LO-1:0]} == wi) grp_d[gi] = word(widx);
        end
    end
end
reg [DATA_W-1:0] grp_q [0:(1<<MUX_HI)-1];
reg [MUX_HI-1:0] grp_sel_q;
reg              rd_e, ack_e, err_e;
integer gq;
always @(posedge clk_i) begin
    for (gq = 0; gq < (1 << MUX_HI); gq = gq + 1) grp_q[gq] <= grp_d[gq];
    grp_sel_q <= rq_word[MUX_LO +: MUX_HI];
end

wire latch_snapshot = rq_rd && rq_snap_seq;
wire consumed = latch_snapshot || win_consumed_i;   // either latches the frozen bank
wire overrun = capture_i && pending_q && !consumed;

// STATUS after this cycle's events: set wins over a simultaneous write-one-to-clear.
reg [ST_W-1:0] status_set;
always @(*) begin
    status_set = {ST_W{1'b0}};
    status_set[ILL_LSB +: ILL_W] = illegal_i;
    status_set[OVR_BIT] = overrun;
    status_set[BAD_BIT] = refused;
    // In the cycle after a capture the gyro inputs hold the captured window.
    status_set[GYR_BIT] = win_valid_q && (gyro_flags_i != {GFLG_W{1'b0}});
end
wire [ST_W-1:0] status_clr = wr_status ? rq_wdata[ST_W-1:0] : {ST_W{1'b0}};
wire [ST_W-1:0] status_next = (status_q & ~status_clr) | status_set;

reg [DATA_W-1:0] reg_rdata_q;
reg        reg_ack_q;
reg        reg_err_q;
assign reg_rdata_o = reg_rdata_q;
assign reg_ack_o = reg_ack_q;
assign reg_err_o = reg_err_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        enable_q <= 1'b0;
        decode_q <= `OMNILOC_CONTROL_DECODE_X4;
        stream_q <= 1'b0;
        filter_q <= {FLT_W{1'b0}};
        period_q <= DEFAULT_PERIOD_CYCLES;
        status_q <= {ST_W{1'b0}};
        win_valid_q <= 1'b0;
        seq_q <= {DATA_W{1'b0}};
        win_ts_q <= {DATA_W{1'b0}};
        win_status_q <= {BYTE_W{1'b0}};
        pending_q <= 1'b0;
        rd_e <= 1'b0;
        ack_e <= 1'b0;
        err_e <= 1'b0;
        reg_rdata_q <= {DATA_W{1'b0}};
        reg_ack_q <= 1'b0;
        reg_err_q <= 1'b0;
    end else begin
        if (wr_control) begin
            enable_q <= rq_wdata[`OMNILOC_CONTROL_ENABLE_LSB];
            decode_q <= wdecode;
            stream_q <= rq_wdata[`OMNILOC_CONTROL_STREAM_LSB];
        end
        if (wr_filter) filter_q <= rq_wdata[`OMNILOC_FILTER_LENGTH_LSB +: FLT_W];
        if (wr_period) period_q <= rq_wdata;
        status_q <= status_next;

        win_valid_q <= capture_i;
        if (capture_i) begin
            seq_q <= seq_q + 1'b1;
            win_ts_q <= timestamp_i;
            win_status_q <= {{(BYTE_W - ST_W){1'b0}}, status_next};
            pending_q <= 1'b1;
        end else if (consumed) begin
            pending_q <= 1'b0;
        end

        // Stage E answer, then stage O.
        rd_e  <= rq_rd && rq_known;
        ack_e <= rq_rd || rq_wr || rq_both;
        err_e <= rq_both || (rq_rd && !rq_known) || (rq_wr && (!rq_known || !rq_writable)) || refused;
        reg_ack_q   <= ack_e;
        reg_err_q   <= err_e;
        reg_rdata_q <= rd_e ? grp_q[grp_sel_q] : {DATA_W{1'b0}};
    end
end

// The bank is copied as it stands before this edge, so it is one window even when a capture
// happens in the same cycle (the new window goes to the live bank, not the frozen one).
always @(posedge clk_i) begin
    if (consumed) begin
        fz_body_q[W_SEQ +: DATA_W] <= seq_q;
        fz_body_q[W_TS +: DATA_W] <= win_ts_q;
        fz_body_q[W_COUNT +: CH*DATA_W] <= win_count_i;
        fz_body_q[W_DIR +: BDIR_W] <= {{(BDIR_W - DIR_W){1'b0}}, win_dir_i};
        fz_body_q[W_STAT +: BYTE_W] <= win_status_q;
        fz_body_q[W_GSUM +: BGSUM_W] <= gyro_sum_ext;
        fz_body_q[W_GCNT +: GCNT_W] <= gyro_count_i;
        fz_body_q[W_GFLG +: GFLG_W] <= gyro_flags_i;
        fz_pos_q <= win_position_i;
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);

always @(*) begin
    if (f_past_valid && !rst_i) begin
        // A refused value never gets into the datapath.
        assert (decode_q <= `OMNILOC_CONTROL_DECODE_MAX);
        assert (period_q >= PERIOD_MIN_CYCLES);
        assert (win_status_q[BYTE_W-1:ST_W] == {(BYTE_W - ST_W){1'b0}});
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // Every request takes effect one cycle later (stage E) and is answered one more cycle after.
        assert ((rq_rd || rq_wr || rq_both) == ($past(reg_rd_i) || $past(reg_wr_i)));
        assert (ack_e == $past(rq_rd || rq_wr || rq_both));
        assert (reg_ack_q == $past(ack_e) && reg_err_q == $past(err_e));
        // A refused or erroneous write leaves the control registers unchanged.
        if (err_e) begin
            assert (enable_q == $past(enable_q) && decode_q == $past(decode_q));
            assert (filter_q == $past(filter_q) && period_q == $past(period_q));
        end
        // Sticky flags: an event is never lost, even against a simultaneous clear.
        if ($past(refused)) assert (status_q[BAD_BIT]);
        if ($past(overrun)) assert (status_q[OVR_BIT]);
        if ($past(illegal_i) != 4'd0) assert ((status_q[ILL_LSB +: 4] & $past(illegal_i)) == $past(illegal_i));
        // A flag only clears on a write of one to it.
        if (($past(status_q) & ~status_q) != {ST_W{1'b0}}) assert ($past(wr_status));
        // The sequence number moves only at a capture, by one.
        if ($past(capture_i)) assert (seq_q == $past(seq_q) + 32'd1);
        else assert (seq_q == $past(seq_q));
        assert (win_valid_q == $past(capture_i));
    end
end

// ---- Independent reference of the bus, the snapshot, OVERRUN and the timestamp ----
localparam integer ADDR_W = `OMNILOC_ADDR_W;
// The request as it takes effect (stage E), from the bus wires alone.
reg              f_rq_rd = 1'b0, f_rq_wr = 1'b0;
reg [ADDR_W-1:0] f_rq_addr = {ADDR_W{1'b0}};
reg [DATA_W-1:0] f_rq_wdata = {DATA_W{1'b0}};
always @(posedge clk_i) begin
    f_rq_rd <= !rst_i && reg_rd_i && !reg_wr_i;
    f_rq_wr <= !rst_i && reg_wr_i && !reg_rd_i;
    f_rq_addr <= reg_addr_i;
    f_rq_wdata <= reg_wdata_i;
end
// The frozen bank is latched by a read of SNAP_SEQ or by the link consuming the window.
// (In the very first cycle, during the reset, the request register still holds its power-up value,
// which the reference cannot know: there it follows the design.)
wire f_latch = (f_rq_rd && f_rq_addr == `OMNILOC_REG_SNAP_SEQ) || win_consumed_i
            || (!f_past_valid && latch_snapshot);
// What the snapshot must hold: the live bank of one latch edge.
reg [DATA_W-1:0]    f_s_seq = {DATA_W{1'b0}}, f_s_ts = {DATA_W{1'b0}};
reg [CH*DATA_W-1:0] f_s_count = {CH*DATA_W{1'b0}}, f_s_pos = {CH*DATA_W{1'b0}};
reg [DIR_W-1:0]     f_s_dir = {DIR_W{1'b0}};
reg [BYTE_W-1:0]    f_s_status = {BYTE_W{1'b0}};
reg [GSUM_W-1:0]    f_s_gsum = {GSUM_W{1'b0}};
reg [GCNT_W-1:0]    f_s_gcnt = {GCNT_W{1'b0}};
reg [GFLG_W-1:0]    f_s_gflg = {GFLG_W{1'b0}};
reg                 f_after_capture = 1'b0;
// A window captured and not yet latched; the timestamp of the last capture.
reg                 f_pending = 1'b0;
reg [DATA_W-1:0]    f_win_ts = {DATA_W{1'b0}};
always @(posedge clk_i) begin
    if (f_latch) begin
        f_s_seq <= seq_q;
        f_s_ts <= win_ts_q;
        f_s_count <= win_count_i;
        f_s_pos <= win_position_i;
        f_s_dir <= win_dir_i;
        f_s_status <= win_status_q;
        f_s_gsum <= gyro_sum_i;
        f_s_gcnt <= gyro_count_i;
        f_s_gflg <= gyro_flags_i;
    end
    f_after_capture <= !rst_i && capture_i;
    if (rst_i) begin
        f_pending <= 1'b0;
        f_win_ts <= {DATA_W{1'b0}};
    end else begin
        if (capture_i) f_pending <= 1'b1;
        else if (f_latch) f_pending <= 1'b0;
        if (capture_i) f_win_ts <= timestamp_i;
    end
end
// OVERRUN must be set exactly by a capture while the previous window is still pending.
wire f_overrun = capture_i && f_pending && !f_latch;
reg [ST_W-1:0] f_set;
always @(*) begin
    f_set = {ST_W{1'b0}};
    f_set[ILL_LSB +: ILL_W] = illegal_i;
    f_set[OVR_BIT] = f_overrun;
    f_set[BAD_BIT] = refused;
    f_set[GYR_BIT] = f_after_capture && (gyro_flags_i != {GFLG_W{1'b0}});
end
wire [ST_W-1:0] f_clr = (f_rq_wr && f_rq_addr == `OMNILOC_REG_STATUS) ? f_rq_wdata[ST_W-1:0] : {ST_W{1'b0}};

// The word each readable address must return, at the edge the read takes effect.
reg [DATA_W-1:0] f_word;
always @(*) begin
    f_word = {DATA_W{1'b0}};
    case (f_rq_addr)
        `OMNILOC_REG_ID: f_word = `OMNILOC_ID;
        `OMNILOC_REG_VERSION: f_word = `OMNILOC_VERSION;
        `OMNILOC_REG_CONTROL: begin
            f_word[`OMNILOC_CONTROL_ENABLE_LSB] = enable_q;
            f_word[DEC_LSB +: DEC_W] = decode_q;
            f_word[`OMNILOC_CONTROL_STREAM_LSB] = stream_q;
        end
        `OMNILOC_REG_FILTER: f_word[FLT_W-1:0] = filter_q;
        `OMNILOC_REG_PERIOD: f_word = period_q;
        `OMNILOC_REG_STATUS: f_word[ST_W-1:0] = status_q;
        `OMNILOC_REG_TIMESTAMP: f_word = timestamp_i;
        `OMNILOC_REG_SNAP_SEQ: f_word = seq_q;
        `OMNILOC_REG_SNAP_TIMESTAMP: f_word = f_s_ts;
        `OMNILOC_REG_SNAP_DIR: f_word[DIR_W-1:0] = f_s_dir;
        `OMNILOC_REG_SNAP_STATUS: f_word[BYTE_W-1:0] = f_s_status;
        `OMNILOC_REG_SNAP_COUNT0: f_word = f_s_count[31:0];
        `OMNILOC_REG_SNAP_COUNT1: f_word = f_s_count[63:32];
        `OMNILOC_REG_SNAP_COUNT2: f_word = f_s_count[95:64];
        `OMNILOC_REG_SNAP_COUNT3: f_word = f_s_count[127:96];
        `OMNILOC_REG_SNAP_POSITION0: f_word = f_s_pos[31:0];
        `OMNILOC_REG_SNAP_POSITION1: f_word = f_s_pos[63:32];
        `OMNILOC_REG_SNAP_POSITION2: f_word = f_s_pos[95:64];
        `OMNILOC_REG_SNAP_POSITION3: f_word = f_s_pos[127:96];
        `OMNILOC_REG_ERROR_COUNT0: f_word = {24'd0, err_count_i[7:0]};
        `OMNILOC_REG_ERROR_COUNT1: f_word = {24'd0, err_count_i[15:8]};
        `OMNILOC_REG_ERROR_COUNT2: f_word = {24'd0, err_count_i[23:16]};
        `OMNILOC_REG_ERROR_COUNT3: f_word = {24'd0, err_count_i[31:24]};
        `OMNILOC_REG_SNAP_GYRO_SUM: f_word = {{(DATA_W - GSUM_W){f_s_gsum[GSUM_W-1]}}, f_s_gsum};
        `OMNILOC_REG_SNAP_GYRO: f_word = {{(DATA_W - 16){1'b0}}, f_s_gflg, f_s_gcnt};
        `OMNILOC_REG_CONFIG: f_word = CHANNELS;
        default: f_word = {DATA_W{1'b0}};
    endcase
end
wire f_known = `OMNILOC_ADDR_KNOWN(f_rq_addr) && (f_rq_addr != `OMNILOC_REG_LINK_ERRORS)
            && (f_rq_addr != `OMNILOC_REG_GYRO_STATE);
// ... carried to the answer two edges later.
reg              f_rd1 = 1'b0, f_rd2 = 1'b0;
reg [DATA_W-1:0] f_exp1 = {DATA_W{1'b0}}, f_exp2 = {DATA_W{1'b0}};
reg [ADDR_W-1:0] f_addr1 = {ADDR_W{1'b0}}, f_addr2 = {ADDR_W{1'b0}};
always @(posedge clk_i) begin
    f_rd1 <= !rst_i && f_rq_rd && f_known;
    f_rd2 <= !rst_i && f_rd1;
    f_exp1 <= f_word;
    f_exp2 <= f_exp1;
    f_addr1 <= f_rq_addr;
    f_addr2 <= f_addr1;
end

// The body of the frozen bank in the WINDOW layout, from the shadows.
reg [8*BODY_BYTES-1:0] f_body;
always @(*) begin
    f_body = {8*BODY_BYTES{1'b0}};
    f_body[W_SEQ +: DATA_W] = f_s_seq;
    f_body[W_TS +: DATA_W] = f_s_ts;
    f_body[W_COUNT +: CH*DATA_W] = f_s_count;
    f_body[W_DIR +: DIR_W] = f_s_dir;
    f_body[W_STAT +: BYTE_W] = f_s_status;
    f_body[W_GSUM +: BGSUM_W] = {{(BGSUM_W - GSUM_W){f_s_gsum[GSUM_W-1]}}, f_s_gsum};
    f_body[W_GCNT +: GCNT_W] = f_s_gcnt;
    f_body[W_GFLG +: GFLG_W] = f_s_gflg;
end

always @(*) begin
    // The pipeline registers are what the reference says (auxiliary invariants for the induction;
    // also in a reset cycle, when a request still in the pipeline may latch the bank).
    if (f_past_valid) begin
        assert (rq_rd == f_rq_rd && rq_wr == f_rq_wr);
        assert (rq_snap_seq == (f_rq_addr == `OMNILOC_REG_SNAP_SEQ));
        assert (rq_status == (f_rq_addr == `OMNILOC_REG_STATUS));
        assert (rq_known == f_known && rq_wdata == f_rq_wdata);
        assert (rq_word == f_rq_addr[MUX_LO+MUX_HI-1:0]);
        assert (rd_e == f_rd1);
        if (rd_e) assert (grp_sel_q == f_addr1[MUX_LO +: MUX_HI] && grp_q[grp_sel_q] == f_exp1);
        // Snapshot coherence: every field of the frozen bank is from the same latch edge.
        assert (fz_body_q == f_body);
        assert (fz_pos_q == f_s_pos);
        // The bank read out byte by byte.
        assert (bank_byte_o == ((bank_idx_i < LAST_IDX) ? f_body[8*bank_idx_i +: 8] : 8'd0));
        // OVERRUN bookkeeping and the window timestamp: the time of the capture.
        assert (pending_q == f_pending);
        assert (win_valid_q == f_after_capture);
        assert (win_ts_q == f_win_ts);
        assert (win_timestamp_o == f_win_ts);
        // The read answer: the register of the address read, 0 for anything else.
        if (reg_ack_q) assert (reg_rdata_q == (f_rd2 ? f_exp2 : {DATA_W{1'b0}}));
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // STATUS exactly: the flags of the cycle set, a write of ones clears (set wins).
        assert (status_q == (($past(status_q) & ~$past(f_clr)) | $past(f_set)));
        if ($past(f_overrun)) assert (status_q[OVR_BIT]);
    end
end

// Each property reachable.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (reg_ack_q && f_rd2 && f_addr2 == `OMNILOC_REG_SNAP_COUNT1 && reg_rdata_q != f_s_count[31:0]);
        cover (reg_ack_q && f_rd2 && f_addr2 == `OMNILOC_REG_SNAP_TIMESTAMP && reg_rdata_q != 0);
        cover (status_q[OVR_BIT] && !$past(status_q[OVR_BIT]));
        cover ($past(status_q[OVR_BIT]) && !status_q[OVR_BIT]);
        cover ($past(capture_i && f_pending && f_latch) && !status_q[OVR_BIT]);
        cover (bank_idx_i == 8'd12 && bank_byte_o != 8'd0);
        cover (win_ts_q != 0 && f_s_ts == win_ts_q);
        // A negative gyro window read back sign-extended, and a gyro fault reaching STATUS.
        cover (reg_ack_q && f_rd2 && f_addr2 == `OMNILOC_REG_SNAP_GYRO_SUM && reg_rdata_q[DATA_W-1]);
        cover (status_q[GYR_BIT] && !$past(status_q[GYR_BIT]));
    end
end
`endif

endmodule

`resetall
