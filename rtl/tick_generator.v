// tick_generator: the window clock of the encoder core (paper section 2.2: 40 MHz -> 100 Hz).
// The defaults are the paper's clock and the window rate (OMNILOC_PAPER_CLOCK_HZ, OMNILOC_TICK_HZ of
// common/regmap.json); the board top sets its own 12 MHz.
//
// Emits a one-cycle tick_o exactly every period cycles and a free-running timestamp.
// The period is sampled at each tick (at reset it is CLK_HZ / TICK_HZ), so a new value written
// to the PERIOD register takes effect at the next tick and never makes a window ragged.
// The first tick comes CLK_HZ / TICK_HZ cycles after the last reset cycle.
//
// Assumptions (assumed/asserted in the FORMAL block):
//   - period_i >= 2 whenever it is sampled (the register file refuses values below
//     PERIOD_MIN_CYCLES = 64) and CLK_HZ / TICK_HZ >= 2.
//   - rst_i is synchronous, active high.
// Guarantees (proven by k-induction): the distance between two ticks equals the period sampled
// at the first of them; the period in force changes only at a tick; the timestamp advances by one.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module tick_generator #(
    parameter integer CLK_HZ = `OMNILOC_PAPER_CLOCK_HZ,
    parameter integer TICK_HZ = `OMNILOC_TICK_HZ
) (
    input  wire        clk_i,
    input  wire        rst_i,
    // Period of the next window in clock cycles; sampled at each tick.
    input  wire [`OMNILOC_PERIOD_CYCLES_W-1:0] period_i,
    output wire        tick_o,
    // Period in force for the current window.
    output wire [`OMNILOC_PERIOD_CYCLES_W-1:0] period_o,
    // Free-running clock-cycle counter, wraps at 2^32.
    output wire [`OMNILOC_DATA_W-1:0] timestamp_o
);

localparam integer P_W = `OMNILOC_PERIOD_CYCLES_W;   // PERIOD.CYCLES
localparam integer TS_W = `OMNILOC_DATA_W;           // TIMESTAMP
localparam [P_W-1:0] DEFAULT_PERIOD_CYCLES = CLK_HZ / TICK_HZ;

// Counts down from the period to one; the cycle after it reads one is the tick, so tick_o is a
// plain flop. The counter is split in halves so that no carry chain is P_W bits long and nothing
// but registered flags decides: lo_zero_q / lo_one_q (low half 0 / 1) and hi_zero_q (high half 0)
// are kept in step with the count (from the period at a reload, from the halves when counting).
localparam integer LO_W = P_W / 2;
localparam integer HI_W = P_W - LO_W;
localparam [LO_W-1:0] LO_ONE = {{(LO_W-1){1'b0}}, 1'b1};
localparam [HI_W-1:0] HI_ONE = {{(HI_W-1){1'b0}}, 1'b1};
reg [LO_W-1:0] lo_q;
reg [HI_W-1:0] hi_q;
reg            lo_zero_q, lo_one_q, hi_zero_q;
wire           at_one = lo_one_q && hi_zero_q;   // the count is 1: the last cycle of the window
reg [P_W-1:0]  period_q;
reg            tick_q;
reg [TS_W-1:0] timestamp_q;

assign tick_o = tick_q;
assign period_o = period_q;
assign timestamp_o = timestamp_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        {hi_q, lo_q} <= DEFAULT_PERIOD_CYCLES;
        lo_zero_q <= (DEFAULT_PERIOD_CYCLES[LO_W-1:0] == {LO_W{1'b0}});
        lo_one_q <= (DEFAULT_PERIOD_CYCLES[LO_W-1:0] == LO_ONE);
        hi_zero_q <= (DEFAULT_PERIOD_CYCLES[P_W-1:LO_W] == {HI_W{1'b0}});
        period_q <= DEFAULT_PERIOD_CYCLES;
        tick_q <= 1'b0;
        timestamp_q <= {TS_W{1'b0}};
    end else begin
        timestamp_q <= timestamp_q + 1'b1;
        tick_q <= at_one;
        if (at_one) begin
            {hi_q, lo_q} <= period_i;
            lo_zero_q <= (period_i[LO_W-1:0] == {LO_W{1'b0}});
            lo_one_q <= (period_i[LO_W-1:0] == LO_ONE);
            hi_zero_q <= (period_i[P_W-1:LO_W] == {HI_W{1'b0}});
            period_q <= period_i;
        end else begin
            lo_q <= lo_q - LO_ONE;
            lo_zero_q <= lo_one_q;
            lo_one_q <= (lo_q == LO_ONE + LO_ONE);
            if (lo_zero_q) begin
                hi_q <= hi_q - HI_ONE;
                hi_zero_q <= (hi_q == HI_ONE);
            end
        end
    end
end

`ifdef FORMAL
// Formal harness: prove exact tick spacing against an independent cycle counter.
wire [P_W-1:0] remain_q = {hi_q, lo_q} - {{(P_W-1){1'b0}}, 1'b1};    // cycles left after this one
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
initial assume (rst_i);

// Cycles since the last tick (or since reset); at a tick it holds the distance to the previous one.
reg [31:0] f_since = 32'd0;
// Period of the window that ends at the next tick.
reg [31:0] f_ending_period = DEFAULT_PERIOD_CYCLES;
always @(posedge clk_i) begin
    if (rst_i) begin
        f_since <= 32'd0;
        f_ending_period <= DEFAULT_PERIOD_CYCLES;
    end else begin
        f_since <= tick_q ? 32'd1 : f_since + 32'd1;
        if (at_one) f_ending_period <= period_q;
    end
end

always @(*) begin
    assume (period_i >= 32'd2);
    // Keeps the proof small; the logic does not depend on the value range.
    assume (period_i <= 32'd12);
end

always @(*) begin
    if (f_past_valid && !rst_i) begin
        assert (period_q >= 32'd2 && period_q <= 32'd12);
        assert (f_ending_period >= 32'd2 && f_ending_period <= 32'd12);
        assert (remain_q < period_q);
        // The flags describe the halves (what the split counter relies on).
        assert (lo_zero_q == (lo_q == 0) && lo_one_q == (lo_q == 1) && hi_zero_q == (hi_q == 0));
        if (tick_q) begin
            // Tick spacing: exactly the period of the window that just ended.
            assert (f_since == f_ending_period);
            assert (remain_q == period_q - 32'd1);
        end else begin
            assert (f_since + remain_q == period_q - 32'd1);
        end
    end
end

always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        // The period only changes at a tick.
        if (!tick_q) assert (period_q == $past(period_q));
        // Never two ticks in a row (period >= 2).
        if ($past(tick_q)) assert (!tick_q);
        // The timestamp advances by one every cycle.
        assert (timestamp_q == $past(timestamp_q) + 32'd1);
    end
end

// Each property reachable: a window of the shortest and one of the longest period, a period
// change taking effect at a tick.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (tick_q && f_since == 32'd2);
        cover (tick_q && f_since == 32'd12);
        cover (tick_q && period_q != $past(period_q));
    end
end
`endif

endmodule

`resetall
