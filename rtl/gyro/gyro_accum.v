// gyro_accum: sums the accepted gyro samples of one window and latches the window on tick_i.
//
// A cycle with sample_valid_i and no tick_i takes the sample: it adds the signed sample_i to the
// running sum and 1 to the count, unless the count is already at its maximum (2^COUNT_W - 1): then
// the sample is dropped and the window's overflow flag (flags bit FAULT_W) set, so the sum can
// never overflow (SUM_W = SAMPLE_W + COUNT_W bits hold COUNT_MAX samples of full scale). In a tick
// cycle no sample is taken: the source holds sample_valid_i and sample_i one more cycle (taken_o
// says when a sample was taken or dropped), so the sample lands in the NEW window. fault_i (one bit
// per fault kind, pulses) is ORed into the window's flags (a fault in the tick cycle into the new
// window); every cycle with a fault (or a dropped sample) increments the saturating fault counter
// fault_count_o (since reset, never cleared by a tick).
//
// On tick_i the running sum, count and flags are latched into sum_o, count_o, flags_o and valid_o
// pulses for one cycle (the outputs hold until the next tick); the running values restart. So
// every taken sample lands in exactly one window (proven below by k-induction).
//
// Why the hold-over and not "add in the tick cycle": the running sum is then a plain adder with
// the flip-flops' enable and synchronous reset (1 logic cell a bit on the iCE40), no operand muxes.
//
// Assumptions: rst_i synchronous, active high; sample_i is a two's complement value; tick_i is
// a one-cycle pulse (the source holds a sample at most one cycle).
`resetall
`timescale 1ns / 1ps
`default_nettype none

module gyro_accum #(
    parameter integer SAMPLE_W = 16,   // bits of one sample (LSB of the part)
    parameter integer COUNT_W = 8,     // bits of the per-window sample count
    parameter integer FAULT_W = 4,     // fault kinds coming in on fault_i
    parameter integer FCNT_W = 8       // bits of the saturating fault counter
) (
    input  wire                        clk_i,
    input  wire                        rst_i,
    input  wire                        tick_i,
    input  wire                        sample_valid_i,
    input  wire signed [SAMPLE_W-1:0]  sample_i,
    input  wire [FAULT_W-1:0]          fault_i,
    output wire signed [SAMPLE_W+COUNT_W-1:0] sum_o,
    output wire [COUNT_W-1:0]          count_o,
    output wire [FAULT_W:0]            flags_o,      // bit FAULT_W: a sample dropped (count full)
    output wire                        valid_o,
    output wire [FCNT_W-1:0]           fault_count_o,
    output wire                        taken_o       // sample_valid_i was taken (or dropped)
);

localparam integer SUM_W = SAMPLE_W + COUNT_W;
localparam [COUNT_W-1:0] COUNT_MAX = {COUNT_W{1'b1}};
localparam [FCNT_W-1:0] FCNT_MAX = {FCNT_W{1'b1}};

reg signed [SUM_W-1:0] sum_q, sum_out_q;
reg [COUNT_W-1:0]      count_q, count_out_q;
reg [FAULT_W:0]        flags_q, flags_out_q;
reg                    valid_q;
reg [FCNT_W-1:0]       fcnt_q;

// full_q: count_q == COUNT_MAX, kept as a flip-flop beside the count (no 8-bit compare in front of
// the flags and the fault counter; the equality is proven below).
reg  full_q;
wire full = full_q;
wire take = sample_valid_i && !tick_i;
wire accept = take && !full;
wire drop = take && full;
wire [FAULT_W:0] fault_now = {drop, fault_i};
wire signed [SUM_W-1:0] sample_ext = {{COUNT_W{sample_i[SAMPLE_W-1]}}, sample_i};

assign sum_o = sum_out_q;
assign count_o = count_out_q;
assign flags_o = flags_out_q;
assign valid_o = valid_q;
assign fault_count_o = fcnt_q;
assign taken_o = take;

// Running sum and count: enable = a sample or a tick, synchronous reset = the tick.
always @(posedge clk_i) begin
    if (rst_i || tick_i) begin
        sum_q <= {SUM_W{1'b0}};
        count_q <= {COUNT_W{1'b0}};
        full_q <= 1'b0;
    end else if (accept) begin
        sum_q <= sum_q + sample_ext;
        count_q <= count_q + 1'b1;
        full_q <= count_q == COUNT_MAX - 1'b1;
    end
end

always @(posedge clk_i) begin
    if (rst_i) begin
        flags_q <= {(FAULT_W + 1){1'b0}};
        valid_q <= 1'b0;
        fcnt_q <= {FCNT_W{1'b0}};
    end else begin
        valid_q <= tick_i;
        flags_q <= (tick_i ? {(FAULT_W + 1){1'b0}} : flags_q) | fault_now;
        if (|fault_now && fcnt_q != FCNT_MAX) fcnt_q <= fcnt_q + 1'b1;
    end
end

// The latched window: pure data, qualified by valid_o (zero until the first tick).
always @(posedge clk_i) begin
    if (rst_i) begin
        sum_out_q <= {SUM_W{1'b0}};
        count_out_q <= {COUNT_W{1'b0}};
        flags_out_q <= {(FAULT_W + 1){1'b0}};
    end else if (tick_i) begin
        sum_out_q <= sum_q;
        count_out_q <= count_q;
        flags_out_q <= flags_q;
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);

// Shadow totals since reset (modulo 2^(SUM_W + 4)): everything accepted in, everything latched out.
localparam integer FW = SUM_W + 4;
reg [FW-1:0] f_in_sum = {FW{1'b0}}, f_out_sum = {FW{1'b0}};
reg [FW-1:0] f_in_cnt = {FW{1'b0}}, f_out_cnt = {FW{1'b0}};
// Per kind: a fault of that kind arrived since the last tick (shadow of the flags).
reg [FAULT_W:0] f_seen = {(FAULT_W + 1){1'b0}};
wire [FW-1:0] f_sample = {{(FW - SAMPLE_W){sample_i[SAMPLE_W-1]}}, sample_i};
always @(posedge clk_i) begin
    if (rst_i) begin
        f_in_sum <= {FW{1'b0}};
        f_out_sum <= {FW{1'b0}};
        f_in_cnt <= {FW{1'b0}};
        f_out_cnt <= {FW{1'b0}};
        f_seen <= {(FAULT_W + 1){1'b0}};
    end else begin
        if (accept) begin
            f_in_sum <= f_in_sum + f_sample;
            f_in_cnt <= f_in_cnt + 1'b1;
        end
        if (tick_i) begin
            f_out_sum <= f_out_sum + {{(FW - SUM_W){sum_q[SUM_W-1]}}, sum_q};
            f_out_cnt <= f_out_cnt + {{(FW - COUNT_W){1'b0}}, count_q};
        end
        f_seen <= (tick_i ? {(FAULT_W + 1){1'b0}} : f_seen) | fault_now;
    end
end

wire [FW-1:0] f_sum_ext = {{(FW - SUM_W){sum_q[SUM_W-1]}}, sum_q};
// Bounds of the running sum for count_q samples of SAMPLE_W bits (no overflow possible).
wire [FW-1:0] f_cnt_ext = {{(FW - COUNT_W){1'b0}}, count_q};
wire signed [FW-1:0] f_lo = -$signed(f_cnt_ext << (SAMPLE_W - 1));
wire signed [FW-1:0] f_hi = $signed((f_cnt_ext << (SAMPLE_W - 1)) - f_cnt_ext);

always @(*) begin
    if (f_past_valid && !rst_i) begin
        // Conservation: accepted = latched + running, for both the sum and the count.
        assert (f_in_sum == f_out_sum + f_sum_ext);
        assert (f_in_cnt == f_out_cnt + {{(FW - COUNT_W){1'b0}}, count_q});
        // The running sum stays within what count_q samples can add up to.
        assert ($signed(f_sum_ext) >= f_lo && $signed(f_sum_ext) <= f_hi);
        // The flags are exactly the faults seen in the window.
        assert (flags_q == f_seen);
        assert (full_q == (count_q == COUNT_MAX));
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // A latched window is the running window of the tick cycle.
        if (valid_q) assert (sum_out_q == $past(sum_q) && count_out_q == $past(count_q)
                             && flags_out_q == $past(flags_q));
        if (!valid_q) assert (sum_out_q == $past(sum_out_q) && count_out_q == $past(count_out_q));
        // A sample is dropped only with a full count, and then flagged.
        if ($past(take) && !$past(accept)) assert ($past(full) && flags_q[FAULT_W]);
        // No sample is taken in a tick cycle.
        if ($past(tick_i)) assert (count_q == 0 && sum_q == 0);
        // The fault counter only goes up, by one per fault cycle, and saturates.
        if ($past(|fault_now) && $past(fcnt_q) != FCNT_MAX) assert (fcnt_q == $past(fcnt_q) + 1'b1);
        else assert (fcnt_q == $past(fcnt_q));
    end
end

// Covers: a window of 3 samples latched; a window with a dropped sample; a negative window sum;
// the fault counter saturated.
always @(posedge clk_i) begin
    if (f_past_valid && !rst_i) begin
        cover (valid_q && count_o == 3);
        cover (valid_q && flags_o[FAULT_W]);
        cover (valid_q && sum_o < 0 && count_o == 2);
        cover (fcnt_q == FCNT_MAX);
    end
end
`endif

endmodule

`resetall
